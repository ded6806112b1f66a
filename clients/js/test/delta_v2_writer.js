// Test support: writing version-2 delta bodies (PROTOCOL.md 4.5.1-4.5.2) in JavaScript, to make
// deltas the C++ sample does not (a move of vertices whose triangles all stay, as a slider makes).
// LZMA's range encoder, the mirror of range_decoder.js; the integer codes as 4.5.1 reads them.

import { intModel } from '../src/range_decoder.js';
import { SESSION } from './support.js';

const TOP = 2 ** 24;
const TWO_32 = 2 ** 32;

export class RangeEncoder {
  constructor() {
    this.low = 0; // up to 33 bits: a Number holds it exactly
    this.range = 0xffffffff;
    this.cache = 0;
    this.cacheSize = 1;
    this.bytes = [];
  }

  /** One bit with the adaptive probability probabilities[i] of a 0. */
  bitAt(probabilities, i, bit) {
    const p = probabilities[i];
    const bound = (this.range >>> 11) * p;
    if (bit === 0) {
      this.range = bound;
      probabilities[i] = p + ((2048 - p) >>> 5);
    } else {
      this.low += bound;
      this.range -= bound;
      probabilities[i] = p - (p >>> 5);
    }
    this.#normalize();
  }

  /** `count` bits of `value`, most significant first, each with probability 1/2. */
  direct(value, count) {
    for (let i = count - 1; i >= 0; --i) {
      this.range >>>= 1;
      if (Math.floor(value / 2 ** i) % 2 === 1) this.low += this.range;
      this.#normalize();
    }
  }

  /** v >= 0: its bit length after the leading one in unary, the next bit modelled, the rest direct. */
  uint(model, v) {
    const w = v + 1;
    const length = Math.floor(Math.log2(w));
    for (let n = 0; n < length; ++n) this.bitAt(model.length, Math.min(n, 23), 1);
    this.bitAt(model.length, Math.min(length, 23), 0);
    if (length === 0) return;
    this.bitAt(model.high, length, Math.floor(w / 2 ** (length - 1)) % 2);
    for (let i = length - 2; i >= 0; i -= 32) {
      const count = Math.min(i + 1, 32);
      this.direct(Math.floor(w / 2 ** (i + 1 - count)) % 2 ** count, count);
    }
  }

  sint(model, v) {
    this.uint(model, v >= 0 ? 2 * v : -2 * v - 1);
  }

  /** The body's bytes (the first is always 0). */
  finish() {
    for (let i = 0; i < 5; ++i) this.#shiftLow();
    return Uint8Array.from(this.bytes);
  }

  #normalize() {
    while (this.range < TOP) {
      this.range = (this.range << 8) >>> 0;
      this.#shiftLow();
    }
  }

  #shiftLow() {
    if (this.low < 0xff000000 || this.low >= TWO_32) {
      const carry = this.low >= TWO_32 ? 1 : 0;
      let byte = this.cache;
      do {
        this.bytes.push((byte + carry) & 0xff);
        byte = 0xff;
      } while (--this.cacheSize !== 0);
      this.cache = Math.floor(this.low / TOP) & 0xff;
    }
    ++this.cacheSize;
    this.low = (this.low % TOP) * 256;
  }
}

/**
 * A version-2 delta that only moves vertices: `moves` [{id, position: [dx, dy, dz], normal:
 * [du, dv], offset?}] ascending by id: residuals on the grid and in normal codes, and of the offset
 * along the held normal (PROTOCOL.md 4.5.2 step 5; 0 or absent keeps the previous offset)
 */
export function movesDelta({ sequence, baseTriangleId, baseVertexId, functionVersion = 1, moves }) {
  const coder = new RangeEncoder();
  const count = intModel();
  for (let part = 0; part < 4; ++part) coder.uint(count, 0); // no splits, removals, loose vertices, triangles
  coder.uint(count, moves.length);
  const [gap, offset, position, normal] = [intModel(), intModel(), intModel(), intModel()];
  moves.forEach((move, i) => {
    coder.uint(gap, i === 0 ? move.id : move.id - moves[i - 1].id - 1);
    coder.sint(offset, move.offset ?? 0); // the offset's residual: 0 predicts the held position (4.5.2, 5)
    for (const d of move.position) coder.sint(position, d);
    for (const d of move.normal) coder.sint(normal, d);
  });
  const body = coder.finish();
  const bytes = new Uint8Array(56 + body.length);
  const view = new DataView(bytes.buffer);
  bytes.set([0x49, 0x53, 0x4f, 0x4d, 2, 2]);
  for (let i = 0; i < 16; ++i) bytes[8 + i] = parseInt(SESSION.slice(2 * i, 2 * i + 2), 16);
  view.setBigUint64(24, BigInt(sequence), true);
  view.setBigUint64(40, BigInt(baseTriangleId), true);
  view.setUint32(48, functionVersion, true);
  view.setUint32(52, baseVertexId, true);
  bytes.set(body, 56);
  return bytes;
}

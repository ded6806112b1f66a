// The range decoder of version-2 delta bodies (PROTOCOL.md 4.5.1): LZMA's adaptive binary range
// coder with 11-bit probabilities, and integers as adaptive Exp-Golomb codes on top of it. A port
// of protocol/range_coder.cpp's decoder: every step is 32-bit unsigned integer arithmetic, so it
// reads exactly the bits the C++ encoder wrote.

import { IsomeshError } from './errors.js';

const TOP = 2 ** 24;
const MAX_LENGTH = 62;
/** Values of more than 52 bits cannot be exact Numbers; every such value makes a frame invalid. */
const MAX_SAFE_LENGTH = 52;
const POWERS_OF_TWO = Float64Array.from({ length: 33 }, (_, k) => 2 ** k);

/** A probability (11 bits) that the next bit is 0, starting at one half. */
export function bitModel() {
  return new Uint16Array(1).fill(1024);
}

/**
 * The contexts of one kind of integer: its bit length in unary, and the bit after the leading one
 * (probabilities as bitModel's).
 */
export function intModel() {
  return { length: new Uint16Array(24).fill(1024), high: new Uint16Array(64).fill(1024) };
}

export class RangeDecoder {
  /** @param {Uint8Array} bytes the body: at least 5 bytes, the first 0 */
  constructor(bytes) {
    if (bytes.length < 5 || bytes[0] !== 0) throw bodyError('delta body shorter than 5 bytes or not starting with 0');
    this.bytes = bytes;
    this.offset = 0;
    this.overrun = 0;
    this.range = 0xffffffff;
    this.code = 0;
    for (let i = 0; i < 5; ++i) this.code = ((this.code << 8) | this.#next()) >>> 0;
  }

  #next() {
    if (this.offset < this.bytes.length) return this.bytes[this.offset++];
    if (++this.overrun > 4) throw bodyError('delta body is truncated');
    return 0;
  }

  bit(model) {
    return this.#ones(model, 0, 0, 1);
  }

  /** A bit with the probability probabilities[i] of a 0, which adapts to it. */
  bitAt(probabilities, i) {
    return this.#ones(probabilities, i, i, 1);
  }

  /**
   * Adaptive bits until a 0 or `limit` bits: returns how many 1s were read. Bit j has the
   * probability probabilities[min(first + j, last)] of a 0. One loop serves single bits and the
   * unary lengths of integers, on local copies of the coder's state (the hottest loop of a delta).
   */
  #ones(probabilities, first, last, limit) {
    let { range, code } = this;
    let n = 0;
    while (n < limit) {
      const i = first + n < last ? first + n : last;
      const p = probabilities[i];
      const bound = (range >>> 11) * p;
      const bit = code < bound ? 0 : 1;
      if (bit === 0) {
        range = bound;
        probabilities[i] = p + ((2048 - p) >>> 5);
      } else {
        code -= bound;
        range -= bound;
        probabilities[i] = p - (p >>> 5);
      }
      if (range < TOP) {
        range = (range << 8) >>> 0;
        code = ((code << 8) | this.#next()) >>> 0;
      }
      if (bit === 0) break;
      ++n;
    }
    this.range = range;
    this.code = code;
    return n;
  }

  /** `count` (<= 32) bits, most significant first, each with probability 1/2. */
  direct(count) {
    let { range, code } = this;
    let value = 0;
    for (let i = 0; i < count; ++i) {
      range >>>= 1;
      const bit = code >= range ? 1 : 0;
      if (bit) code -= range;
      value = value * 2 + bit;
      if (range < TOP) {
        range = (range << 8) >>> 0;
        code = ((code << 8) | this.#next()) >>> 0;
      }
    }
    this.range = range;
    this.code = code;
    return value;
  }

  uint(model) {
    const length = this.#ones(model.length, 0, 23, MAX_LENGTH + 1);
    if (length > MAX_LENGTH) throw bodyError('integer longer than 62 bits');
    if (length === 0) return 0;
    let v = 2 + this.bitAt(model.high, length);
    for (let i = length - 2; i >= 0; i -= 32) {
      const count = Math.min(i + 1, 32);
      v = v * POWERS_OF_TWO[count] + this.direct(count);
    }
    if (length > MAX_SAFE_LENGTH) throw bodyError('integer out of range');
    return v - 1;
  }

  sint(model) {
    const z = this.uint(model);
    return z % 2 === 0 ? z / 2 : -(z + 1) / 2;
  }
}

function bodyError(message) {
  return new IsomeshError('bad_frame', message);
}

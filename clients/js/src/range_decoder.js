// The range decoder of version-2 delta bodies (PROTOCOL.md 4.5.1): LZMA's adaptive binary range
// coder with 11-bit probabilities, and integers as adaptive Exp-Golomb codes on top of it. A port
// of protocol/range_coder.cpp's decoder: every step is 32-bit unsigned integer arithmetic, so it
// reads exactly the bits the C++ encoder wrote.

import { IsomeshError } from './errors.js';

const TOP = 2 ** 24;
const MAX_LENGTH = 62;
/** Values of more than 52 bits cannot be exact Numbers; every such value makes a frame invalid. */
const MAX_SAFE_LENGTH = 52;

/** A probability (11 bits) that the next bit is 0. */
export function bitModel() {
  return { p: 1024 };
}

/** The contexts of one kind of integer: its bit length in unary, and the bit after the leading one. */
export function intModel() {
  return { length: Array.from({ length: 24 }, bitModel), high: Array.from({ length: 64 }, bitModel) };
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

  #normalize() {
    if (this.range < TOP) {
      this.range = (this.range << 8) >>> 0;
      this.code = ((this.code << 8) | this.#next()) >>> 0;
    }
  }

  bit(model) {
    const bound = (this.range >>> 11) * model.p;
    let bit;
    if (this.code < bound) {
      this.range = bound;
      model.p += (2048 - model.p) >>> 5;
      bit = 0;
    } else {
      this.code -= bound;
      this.range -= bound;
      model.p -= model.p >>> 5;
      bit = 1;
    }
    this.#normalize();
    return bit;
  }

  /** `count` (<= 32) bits, most significant first, each with probability 1/2. */
  direct(count) {
    let value = 0;
    for (let i = 0; i < count; ++i) {
      this.range = this.range >>> 1;
      const bit = this.code >= this.range ? 1 : 0;
      if (bit) this.code -= this.range;
      value = value * 2 + bit;
      this.#normalize();
    }
    return value;
  }

  uint(model) {
    let length = 0;
    while (this.bit(model.length[Math.min(length, 23)]) === 1) {
      if (++length > MAX_LENGTH) throw bodyError('integer longer than 62 bits');
    }
    if (length === 0) return 0;
    let v = 2 + this.bit(model.high[length]);
    for (let i = length - 2; i >= 0; i -= 32) {
      const count = Math.min(i + 1, 32);
      v = v * 2 ** count + this.direct(count);
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

// Variable-length integers of the id lists in binary frames (PROTOCOL.md, "Id lists").
//
// Unsigned LEB128: 7 bits per byte, least significant group first, the high bit set on every byte
// but the last; only the shortest form is valid. Triangle ids stay below 2^53, so every value a
// valid frame holds is an exact JavaScript Number; anything larger is rejected as malformed.

import { IsomeshError } from './errors.js';

/** Largest triangle id of the protocol: 2^53 - 1, Number.MAX_SAFE_INTEGER. */
export const MAX_TRIANGLE_ID = Number.MAX_SAFE_INTEGER;

const TWO_POW_53 = 2 ** 53;

/**
 * Reads one varint of `bytes` (a Uint8Array) at `state.offset` and advances the offset.
 * Returns a Number below 2^53; larger values (up to 2^64 - 1) come back as a BigInt. Throws
 * IsomeshError('bad_frame') on truncation, a non-shortest form or more than 64 bits.
 */
export function readVarint(bytes, state) {
  let value = 0;
  let scale = 1; // 128^i, exact in a double
  for (let i = 0; i < MAX_VARINT_BYTES; ++i) {
    const offset = state.offset + i;
    if (offset >= bytes.length) throw frameError('truncated varint');
    const byte = bytes[offset];
    value += (byte & 0x7f) * scale;
    if ((byte & 0x80) === 0) {
      if (byte === 0 && i > 0) throw frameError('varint not in its shortest form');
      if (i === MAX_VARINT_BYTES - 1 && byte > 1) throw frameError('varint exceeds 64 bits');
      const start = state.offset;
      state.offset = offset + 1;
      return value < TWO_POW_53 ? value : bigVarint(bytes, start, offset);
    }
    scale *= 128;
  }
  throw frameError('varint exceeds 64 bits');
}

/** Reads a varint that must be a safe integer (an id, a count). */
export function readSafeVarint(bytes, state) {
  const value = readVarint(bytes, state);
  if (typeof value === 'bigint') throw frameError('varint exceeds 2^53 - 1');
  return value;
}

const MAX_VARINT_BYTES = 10;

function bigVarint(bytes, first, last) {
  let value = 0n;
  for (let offset = last; offset >= first; --offset) {
    value = (value << 7n) | BigInt(bytes[offset] & 0x7f);
  }
  return value;
}

/** Appends the LEB128 form of a non-negative safe integer to `out` (an array of bytes). */
export function appendVarint(out, value) {
  if (!Number.isSafeInteger(value) || value < 0) {
    throw new RangeError(`varint value must be a non-negative safe integer, got ${value}`);
  }
  while (value >= 128) {
    out.push((value % 128) | 0x80);
    value = Math.floor(value / 128);
  }
  out.push(value);
  return out;
}

/**
 * Decodes exactly `count` strictly ascending ids, each <= maxId, using all of `bytes`: the first
 * id, then each difference to the previous one (>= 1).
 */
export function decodeSortedIds(bytes, count, maxId = MAX_TRIANGLE_ID) {
  const ids = new Array(count);
  const state = { offset: 0 };
  let previous = -1;
  for (let i = 0; i < count; ++i) {
    const step = readSafeVarint(bytes, state);
    if (i > 0 && step === 0) throw frameError('sorted ids repeat');
    const id = i === 0 ? step : previous + step;
    if (id > maxId) throw frameError(`id ${id} exceeds ${maxId}`);
    ids[i] = id;
    previous = id;
  }
  if (state.offset !== bytes.length) throw frameError('trailing bytes after sorted ids');
  return ids;
}

/** The inverse of decodeSortedIds. Precondition: `ids` strictly ascending. */
export function encodeSortedIds(ids) {
  const out = [];
  ids.forEach((id, i) => appendVarint(out, i === 0 ? id : id - ids[i - 1]));
  return Uint8Array.from(out);
}

/** Zigzag: 0, -1, 1, -2, ... <- 0, 1, 2, 3, ... (a Number or a BigInt, as readVarint gives). */
export function unzigzag(u) {
  if (typeof u === 'bigint') return u % 2n === 0n ? u / 2n : -(u + 1n) / 2n;
  return u % 2 === 0 ? u / 2 : -(u + 1) / 2;
}

export function zigzag(n) {
  return n >= 0 ? 2 * n : -2 * n - 1;
}

/**
 * Decodes exactly `count` ids in any order, each <= maxId, using all of `bytes`: each id minus the
 * previous one (the first minus `base`), zigzag-mapped. Does not check distinctness.
 */
export function decodeIdSequence(bytes, count, base, maxId = MAX_TRIANGLE_ID) {
  const ids = new Array(count);
  const state = { offset: 0 };
  let previous = base;
  for (let i = 0; i < count; ++i) {
    const step = unzigzag(readVarint(bytes, state));
    const id = typeof step === 'bigint' ? safeSum(previous, step) : previous + step;
    if (!(id >= 0 && id <= maxId)) throw frameError(`id ${id} is outside [0, ${maxId}]`);
    ids[i] = id;
    previous = id;
  }
  if (state.offset !== bytes.length) throw frameError('trailing bytes after the id sequence');
  return ids;
}

/** The inverse of decodeIdSequence. */
export function encodeIdSequence(ids, base) {
  const out = [];
  let previous = base;
  for (const id of ids) {
    appendVarint(out, zigzag(id - previous));
    previous = id;
  }
  return Uint8Array.from(out);
}

/** previous + step for a step beyond 2^53: exact, or NaN when the sum is no safe integer. */
function safeSum(previous, step) {
  const sum = BigInt(previous) + step;
  return sum >= 0n && sum <= BigInt(MAX_TRIANGLE_ID) ? Number(sum) : NaN;
}

function frameError(message) {
  return new IsomeshError('bad_frame', message);
}

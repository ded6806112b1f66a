import assert from 'node:assert/strict';
import { test } from 'node:test';

import {
  appendVarint,
  decodeIdSequence,
  decodeSortedIds,
  encodeIdSequence,
  encodeSortedIds,
  readVarint,
  unzigzag,
  zigzag,
} from '../src/varint.js';

const read = (bytes) => {
  const state = { offset: 0 };
  const value = readVarint(Uint8Array.from(bytes), state);
  return { value, offset: state.offset };
};

const rejects = (fn, pattern) => assert.throws(fn, (e) => e.code === 'bad_frame' && pattern.test(e.message));

test('readVarint: LEB128 examples', () => {
  assert.deepEqual(read([0]), { value: 0, offset: 1 });
  assert.deepEqual(read([0x7f]), { value: 127, offset: 1 });
  assert.deepEqual(read([0x80, 0x01]), { value: 128, offset: 2 });
  assert.deepEqual(read([0xe5, 0x8e, 0x26]), { value: 624485, offset: 3 });
});

test('readVarint: round trips up to 2^53 - 1', () => {
  for (const value of [1, 300, 2 ** 31, 2 ** 32 + 7, 2 ** 49 - 1, Number.MAX_SAFE_INTEGER]) {
    assert.equal(read(appendVarint([], value)).value, value);
  }
});

test('readVarint: values from 2^53 to 2^64 - 1 come back exact as BigInt', () => {
  assert.equal(read([0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x10]).value, 2n ** 53n);
  const max = [0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01];
  assert.equal(read(max).value, 2n ** 64n - 1n);
});

test('readVarint: rejects truncation, non-shortest forms and more than 64 bits', () => {
  rejects(() => read([]), /truncated/);
  rejects(() => read([0x80]), /truncated/);
  rejects(() => read([0x80, 0x00]), /shortest/);
  rejects(() => read([0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x02]), /64 bits/);
  rejects(() => read([0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x81, 0x00]), /64 bits/);
});

test('zigzag maps 0, -1, 1, -2 to 0, 1, 2, 3 and back', () => {
  assert.deepEqual([0, -1, 1, -2, 2].map(zigzag), [0, 1, 2, 3, 4]);
  for (const n of [0, -1, 1, -1000, 1000, -(2 ** 40)]) assert.equal(unzigzag(zigzag(n)), n);
  assert.equal(unzigzag(2n ** 54n - 1n), -(2n ** 53n));
});

test('sorted ids: first id then differences', () => {
  const ids = [3, 4, 200, 2 ** 40, Number.MAX_SAFE_INTEGER];
  const bytes = encodeSortedIds(ids);
  assert.deepEqual([...bytes.subarray(0, 3)], [3, 1, 196]);
  assert.deepEqual(decodeSortedIds(bytes, ids.length), ids);
  assert.deepEqual(decodeSortedIds(new Uint8Array(0), 0), []);
});

test('sorted ids: rejects repeats, ids over the bound, trailing and missing bytes', () => {
  rejects(() => decodeSortedIds(Uint8Array.from([5, 0]), 2), /repeat/);
  rejects(() => decodeSortedIds(Uint8Array.from([5, 3]), 2, 7), /exceeds/);
  rejects(() => decodeSortedIds(Uint8Array.from([5, 1, 1]), 2), /trailing/);
  rejects(() => decodeSortedIds(Uint8Array.from([5]), 2), /truncated/);
  rejects(() => decodeSortedIds(Uint8Array.from(appendVarint([1], Number.MAX_SAFE_INTEGER)), 2), /exceeds/);
});

test('id sequences: any order, zigzag differences from a base', () => {
  const ids = [10, 7, 7 + 2 ** 45, 0, 12];
  const bytes = encodeIdSequence(ids, 8);
  assert.equal(bytes[0], zigzag(2));
  assert.deepEqual(decodeIdSequence(bytes, ids.length, 8), ids);
});

test('id sequences: a jump of more than 2^52 decodes exactly', () => {
  const ids = [Number.MAX_SAFE_INTEGER, 0, Number.MAX_SAFE_INTEGER - 5];
  // the second difference is -(2^53 - 1): its zigzag form needs 54 bits
  assert.deepEqual(decodeIdSequence(encodeIdSequenceBig(ids, 0), ids.length, 0), ids);
});

test('id sequences: rejects ids below 0 or over the bound, and trailing bytes', () => {
  rejects(() => decodeIdSequence(Uint8Array.from([zigzag(-3)]), 1, 2), /outside/);
  rejects(() => decodeIdSequence(Uint8Array.from([zigzag(5)]), 1, 2, 6), /outside/);
  rejects(() => decodeIdSequence(Uint8Array.from([2, 2]), 1, 0), /trailing/);
});

/** encodeIdSequence with BigInt arithmetic, for differences beyond 2^53. */
function encodeIdSequenceBig(ids, base) {
  const out = [];
  let previous = BigInt(base);
  for (const id of ids) {
    const d = BigInt(id) - previous;
    let u = d >= 0n ? 2n * d : -2n * d - 1n;
    while (u >= 128n) {
      out.push(Number(u % 128n) | 0x80);
      u /= 128n;
    }
    out.push(Number(u));
    previous = BigInt(id);
  }
  return Uint8Array.from(out);
}

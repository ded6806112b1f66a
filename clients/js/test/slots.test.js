import assert from 'node:assert/strict';
import { test } from 'node:test';

import { TriangleSlots } from '../src/slots.js';
import { random } from './support.js';

/** A triangle's data derived from its id, so that every slot can be checked against its id. */
function fill(slots, slot, id) {
  for (let k = 0; k < 3; ++k) slots.write(slot, k, id * 3 + k, id, k, -id, k, id, 1);
}

function checkContents(slots, model) {
  slots.checkInvariants();
  assert.equal(slots.count, model.size);
  for (const id of model) {
    const s = slots.slotOf(id);
    assert.ok(s < slots.count, `triangle ${id} lies in the live range`);
    const p = slots.positions.subarray(9 * s, 9 * s + 9);
    const n = slots.normals.subarray(9 * s, 9 * s + 9);
    assert.deepEqual([...p], [id, 0, -id, id, 1, -id, id, 2, -id]);
    assert.deepEqual([...n], [0, id, 1, 1, id, 1, 2, id, 1]);
    assert.deepEqual([...slots.vertexIds.subarray(3 * s, 3 * s + 3)], [3 * id, 3 * id + 1, 3 * id + 2]);
  }
}

test('TriangleSlots: insert appends, remove swaps the last triangle into the hole', () => {
  const slots = new TriangleSlots(4);
  for (const id of [10, 11, 12, 13]) fill(slots, slots.insert(id), id);
  assert.equal(slots.remove(11), true);
  assert.equal(slots.count, 3);
  assert.equal(slots.slotOf(13), 1, 'the last triangle moved into the freed slot');
  assert.equal(slots.remove(11), false);
  checkContents(slots, new Set([10, 12, 13]));
});

test('TriangleSlots: inserts fill released slots before appending', () => {
  const slots = new TriangleSlots(8);
  for (const id of [1, 2, 3, 4, 5]) fill(slots, slots.insert(id), id);
  slots.release(2);
  slots.release(4);
  const a = slots.insert(6);
  const b = slots.insert(7);
  assert.deepEqual([a, b].sort(), [1, 3]);
  fill(slots, a, 6);
  fill(slots, b, 7);
  slots.compact();
  checkContents(slots, new Set([1, 3, 5, 6, 7]));
});

test('TriangleSlots: compact handles holes at the end of the range', () => {
  const slots = new TriangleSlots(8);
  for (const id of [1, 2, 3, 4, 5, 6]) fill(slots, slots.insert(id), id);
  for (const id of [6, 5, 1]) slots.release(id);
  slots.compact();
  checkContents(slots, new Set([2, 3, 4]));
  for (const id of [2, 3, 4]) slots.release(id);
  slots.compact();
  checkContents(slots, new Set());
});

test('TriangleSlots: rejects a duplicate id', () => {
  const slots = new TriangleSlots(2);
  slots.insert(1);
  assert.throws(() => slots.insert(1), /already present/);
});

test('TriangleSlots: grows by doubling, keeps contents and counts generations', () => {
  const slots = new TriangleSlots(2);
  const generation = slots.generation;
  const ids = Array.from({ length: 100 }, (_, i) => 1000 + i);
  for (const id of ids) fill(slots, slots.insert(id), id);
  assert.ok(slots.capacity >= 100 && slots.capacity <= 128);
  assert.ok(slots.generation > generation);
  assert.equal(slots.positions.length, 9 * slots.capacity);
  checkContents(slots, new Set(ids));
});

test('TriangleSlots: random batches of releases and inserts match a set model', () => {
  const next = random(12345);
  const slots = new TriangleSlots(16);
  const model = new Set();
  let nextId = 0;
  for (let round = 0; round < 300; ++round) {
    const live = [...model];
    const removals = Math.floor(next() * Math.min(live.length, 20));
    for (let i = 0; i < removals; ++i) {
      const id = live.splice(Math.floor(next() * live.length), 1)[0];
      assert.equal(slots.release(id), true);
      model.delete(id);
    }
    const inserts = Math.floor(next() * 24);
    for (let i = 0; i < inserts; ++i) {
      const id = nextId++;
      fill(slots, slots.insert(id), id);
      model.add(id);
    }
    slots.compact();
    checkContents(slots, model);
    slots.takeDirtyRanges();
  }
});

test('TriangleSlots: dirty ranges cover every written live slot, in at most 32 ranges', () => {
  const next = random(99);
  const slots = new TriangleSlots(4096);
  for (let id = 0; id < 4000; ++id) fill(slots, slots.insert(id), id);
  assert.deepEqual(slots.takeDirtyRanges(), [{ start: 0, count: 4000 }]);
  assert.deepEqual(slots.takeDirtyRanges(), [], 'taking clears the record');

  // Scattered rewrites: every touched slot must be inside a range.
  const touched = new Set();
  for (let i = 0; i < 500; ++i) {
    const s = Math.floor(next() * 4000);
    slots.touch(s);
    touched.add(s);
  }
  const ranges = slots.takeDirtyRanges();
  assert.ok(ranges.length <= 32, `${ranges.length} ranges`);
  for (let i = 1; i < ranges.length; ++i) {
    assert.ok(ranges[i].start >= ranges[i - 1].start + ranges[i - 1].count, 'ascending, disjoint');
  }
  for (const s of touched) {
    assert.ok(ranges.some((r) => s >= r.start && s < r.start + r.count), `slot ${s} is covered`);
  }

  // Slots beyond the live range after a shrink are not reported.
  for (let id = 3990; id < 4000; ++id) slots.release(id);
  slots.compact();
  slots.touch(3995);
  assert.deepEqual(slots.takeDirtyRanges(), []);
});

test('TriangleSlots: a removal moves one triangle and reports just two slots', () => {
  const slots = new TriangleSlots(64);
  for (let id = 0; id < 50; ++id) fill(slots, slots.insert(id), id);
  slots.takeDirtyRanges();
  slots.remove(7);
  fill(slots, slots.insert(99), 99);
  assert.deepEqual(slots.takeDirtyRanges(), [
    { start: 7, count: 1 },
    { start: 49, count: 1 },
  ]);
});

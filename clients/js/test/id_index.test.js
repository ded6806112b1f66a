import assert from 'node:assert/strict';
import { test } from 'node:test';

import { IdIndex, NONE } from '../src/id_index.js';
import { random } from './support.js';

/** Random sets and deletes of ids drawn by `draw`, checked against a Map after every step. */
function matchesMap(draw, steps, seed) {
  const uniform = random(seed);
  const next = () => Math.floor(uniform() * 2 ** 32); // a 32-bit value
  const index = new IdIndex(4);
  const model = new Map();
  for (let step = 0; step < steps; ++step) {
    const id = draw(next);
    if (next() % 3 === 0) {
      assert.equal(index.delete(id), model.delete(id), `delete ${id}`);
    } else {
      index.set(id, step);
      model.set(id, step);
    }
    const probe = draw(next);
    assert.equal(index.get(probe), model.get(probe) ?? NONE, `get ${probe} after step ${step}`);
    assert.equal(index.size, model.size);
  }
  for (const [id, slot] of model) assert.equal(index.get(id), slot);
  assert.deepEqual([...index].sort((a, b) => a[0] - b[0]), [...model].sort((a, b) => a[0] - b[0]));
  assert.deepEqual([...index.keys()].sort((a, b) => a - b), [...model.keys()].sort((a, b) => a - b));
}

test('IdIndex (matches a Map: ascending runs of ids, as a server numbers triangles)', () => {
  let base = 0;
  matchesMap((next) => {
    base += next() % 4 === 0 ? 1 : 0;
    return base + (next() % 200);
  }, 20000, 1);
});

test('IdIndex (matches a Map: ids past 2^32 and up to 2^53 - 1)', () => {
  const bases = [2 ** 32 - 100, 2 ** 40, Number.MAX_SAFE_INTEGER - 300];
  matchesMap((next) => bases[next() % 3] + (next() % 300), 20000, 2);
});

test('IdIndex (matches a Map: ids that all share their low bits, so they collide)', () => {
  matchesMap((next) => (next() % 500) * 2 ** 20, 20000, 3);
});

test('IdIndex (grows and clears)', () => {
  const index = new IdIndex(1);
  for (let id = 0; id < 100000; ++id) index.set(id * 7, id);
  assert.equal(index.size, 100000);
  assert.equal(index.get(7 * 99999), 99999);
  assert.equal(index.get(5), NONE);
  index.clear();
  assert.deepEqual([index.size, index.get(0), [...index].length], [0, NONE, 0]);
});

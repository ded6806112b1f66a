import assert from 'node:assert/strict';
import { test } from 'node:test';

import { formatTick, niceStep, tickValues } from '../src/axes.js';

test('niceStep: 1, 2 or 5 times a power of ten, about 6 intervals', () => {
  assert.equal(niceStep(6), 1);
  assert.equal(niceStep(56), 10);
  assert.equal(niceStep(2.4), 0.5);
  assert.equal(niceStep(12), 2);
  assert.equal(niceStep(0.6), 0.1);
  assert.equal(niceStep(0), 1);
  assert.equal(niceStep(NaN), 1);
});

test('tickValues: multiples of the step inside the range, without float noise', () => {
  assert.deepEqual(tickValues(-3, 3, 1), [-3, -2, -1, 0, 1, 2, 3]);
  assert.deepEqual(tickValues(-0.35, 0.35, 0.1), [-0.3, -0.2, -0.1, 0, 0.1, 0.2, 0.3]);
  assert.deepEqual(tickValues(1.2, 3.2, 1), [2, 3]);
  assert.ok(tickValues(-1e9, 1e9, 1e-9).length <= 1000, 'bounded');
});

test('formatTick: the decimals the step needs, a real minus sign', () => {
  assert.equal(formatTick(2, 1), '2');
  assert.equal(formatTick(-0.5, 0.5), '−0.5');
  assert.equal(formatTick(0.3, 0.1), '0.3');
  assert.equal(formatTick(20, 10), '20');
});

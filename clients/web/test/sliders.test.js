import assert from 'node:assert/strict';
import { test } from 'node:test';

import { DEFAULT_RANGE, rangeFor, snapToStep } from '../src/sliders.js';

test('rangeFor: GeoGebra default -5..5 by 0.1, widened to hold the value', () => {
  assert.deepEqual(rangeFor(1), DEFAULT_RANGE);
  assert.deepEqual(rangeFor(-5), DEFAULT_RANGE);
  assert.deepEqual(rangeFor(7), { min: -10, max: 10, step: 0.2 });
  assert.deepEqual(rangeFor(-30), { min: -40, max: 40, step: 1 });
});

test('snapToStep: on the grid from min, clamped, without float noise', () => {
  assert.equal(snapToStep(1.04, DEFAULT_RANGE), 1);
  assert.equal(snapToStep(0.3000001, DEFAULT_RANGE), 0.3);
  assert.equal(snapToStep(99, DEFAULT_RANGE), 5);
  assert.equal(snapToStep(0.26, { min: 0.05, max: 1, step: 0.1 }), 0.25);
});

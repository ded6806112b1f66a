import assert from 'node:assert/strict';
import { test } from 'node:test';

import { EMPTY_MESSAGE, prepareEquation } from '../src/equation_check.js';

test('prepareEquation: an empty equation gets a message', () => {
  assert.deepEqual(prepareEquation(''), { ok: false, message: EMPTY_MESSAGE });
  assert.deepEqual(prepareEquation('   '), { ok: false, message: EMPTY_MESSAGE });
});

test('prepareEquation: capital X, Y, Z are the coordinates, as in GeoGebra', () => {
  const p = prepareEquation('X^2+Y^2+Z^2=4');
  assert.equal(p.expression, 'x^2+y^2+z^2=4');
  assert.deepEqual(p.notes, ['X, Y, Z read as the coordinates x, y, z.']);
  assert.equal(prepareEquation('XY+z=1').expression, 'xy+z=1', 'a product of coordinates');
  assert.equal(prepareEquation('Xa+R=1').expression, 'Xa+R=1', 'other names keep their case');
  assert.equal(prepareEquation('2X=1E3').expression, '2x=1E3', 'an exponent is no name');
  assert.deepEqual(prepareEquation('x^2+Y=1').notes, ['Y read as the coordinate y.']);
});

test('prepareEquation: no "=" is read as = 0, and says so', () => {
  const p = prepareEquation(' x^2+y^2+z^2 ');
  assert.equal(p.expression, 'x^2+y^2+z^2');
  assert.deepEqual(p.notes, ['No “=”: drawing x^2+y^2+z^2 = 0.']);
  assert.deepEqual(prepareEquation('x^2+y^2+z^2=4').notes, []);
  assert.deepEqual(prepareEquation('x<1').notes, [], 'the server explains inequalities itself');
});

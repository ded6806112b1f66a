import assert from 'node:assert/strict';
import { test } from 'node:test';

import { missingParameters, parameterAttributes, parameterNames, valuesFor } from '../src/parameters.js';

test('parameterNames: names other than coordinates, constants and called functions', () => {
  assert.deepEqual(parameterNames('x^2+y^2+z^2=a'), ['a']);
  assert.deepEqual(parameterNames('(sqrt(x^2+y^2)-R)^2+z^2=r^2'), ['R', 'r']);
  assert.deepEqual(parameterNames('xyz+2cos(2x)=e*pi+π'), [], 'xyz is x*y*z; e, pi, π are constants');
  assert.deepEqual(parameterNames('sin(x)cos(y)+t*t=t2'), ['t', 't2'], 'first use order, once each');
  assert.deepEqual(parameterNames('α x + β_1 = 0'), ['α', 'β_1']);
  assert.deepEqual(parameterNames('max(x, y) + sin = 1'), ['sin'], 'a function name not called is a name');
  assert.deepEqual(parameterNames('2.5e3x + 1e-3 = 0'), [], 'exponents of numbers are not names');
});

test('valuesFor keeps known values and fills the others', () => {
  assert.deepEqual(valuesFor(['a', 'b'], { a: 4, c: 2 }), { a: 4, b: 1 });
  assert.deepEqual(valuesFor(['a'], {}, 0), { a: 0 });
});

test('missingParameters reads the names a bad_field error lists', () => {
  assert.deepEqual(missingParameters({ code: 'bad_field', message: "parameters: no value for parameters 'a', 'β'" }), ['a', 'β']);
  assert.deepEqual(missingParameters({ code: 'bad_field', message: "parameters: no value for parameter 'k'" }), ['k']);
  assert.deepEqual(missingParameters({ code: 'bad_expression', message: "no value for parameter 'k'" }), []);
  assert.deepEqual(missingParameters({ code: 'bad_field', message: 'box: must be an array' }), []);
});

test('parameterAttributes: numeric attributes and the parameters list, not HTML or own attributes', () => {
  const attributes = Object.entries({ equation: 'x=a', a: '4', budget: '100', id: '7', 'data-x': '1', style: '', b: 'wide', r: '2' }).map(
    ([name, value]) => ({ name, value }),
  );
  assert.deepEqual(parameterAttributes(attributes, 'R: 2.5, r=0.7; bad', new Set(['equation', 'budget'])), { a: 4, r: 0.7, R: 2.5 });
});

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { decodeState, encodeState, validBox } from '../src/url_state.js';

const scene = {
  surfaces: [
    { expression: 'x^2+y^2+z^2=a', color: '#3d7fd6', visible: true },
    { expression: 'z=x*y', color: '#d9553d', visible: false },
  ],
  parameters: { a: 4, k: -0.25 },
  sliders: { k: { min: -1, max: 1, step: 0.05 } },
  box: [-3, 3, -2.5, 2.5, -1, 4],
  constraints: { triangles: 50000, max_error: 0.001, error_measure: 'epsilon4' },
  camera: { position: [10.12345, 8, 6], target: [0, 0, 0.5] },
  display: { colorMode: 'height', show: ['axes', 'box'], wireframe: true },
};

test('encodeState/decodeState: a scene survives the round trip through the query string', () => {
  const decoded = decodeState(encodeState(scene));
  assert.deepEqual(decoded.surfaces, scene.surfaces);
  assert.deepEqual(decoded.parameters, scene.parameters);
  assert.deepEqual(decoded.sliders, scene.sliders);
  assert.deepEqual(decoded.box, scene.box);
  assert.deepEqual(decoded.constraints, scene.constraints);
  assert.deepEqual(decoded.camera, { position: [10.123, 8, 6], target: [0, 0, 0.5] }, 'camera rounded to 1/1000');
  assert.deepEqual(decoded.display, scene.display);
});

test('encodeState keeps non-state keys (server) and leaves defaults out', () => {
  const query = encodeState(
    { surfaces: [{ expression: 'x=1', color: '#3d7fd6' }], constraints: { max_error: 0, error_measure: 'distance' }, display: { colorMode: 'uniform', show: ['grid', 'axes', 'box'] } },
    new URLSearchParams('server=ws://h:1/ws&eq=old'),
  );
  const params = new URLSearchParams(query);
  assert.equal(params.get('server'), 'ws://h:1/ws');
  assert.deepEqual(params.getAll('eq'), ['x=1'], 'the old scene is replaced');
  for (const key of ['maxerror', 'measure', 'colormode', 'show', 'wire', 'hidden']) assert.equal(params.has(key), false, key);
});

test('decodeState: null without scene keys; the legacy expr= is one surface', () => {
  assert.equal(decodeState(''), null);
  assert.equal(decodeState('server=ws://h/ws'), null);
  assert.deepEqual(decodeState('expr=x%5E2%3D1').surfaces, [{ expression: 'x^2=1', color: null, visible: true }]);
});

test('decodeState drops what does not parse', () => {
  const s = decodeState('eq=x=1&box=3,-3,-3,3,-3,3&budget=-5&maxerror=abc&measure=bogus&p=a:NaN&p=b:2:5:1:0.1&cam=1,2&colormode=rainbow&color=zzzzzz');
  assert.deepEqual(s.surfaces, [{ expression: 'x=1', color: null, visible: true }]);
  assert.equal(s.box, undefined, 'x0 > x1 is no box');
  assert.equal(s.constraints, undefined);
  assert.deepEqual(s.parameters, { b: 2 }, 'a has no number; b keeps its value');
  assert.equal(s.sliders, undefined, 'min > max is no range');
  assert.equal(s.camera, undefined);
  assert.equal(s.display, undefined);
});

test('decodeState: at most 16 surfaces', () => {
  const query = Array.from({ length: 20 }, (_, i) => `eq=x=${i}`).join('&');
  assert.equal(decodeState(query).surfaces.length, 16);
});

test('validBox', () => {
  assert.ok(validBox([-1, 1, -1, 1, -1, 1]));
  assert.ok(!validBox([1, 1, -1, 1, -1, 1]));
  assert.ok(!validBox([-1, 1, -1, 1, -1]));
  assert.ok(!validBox([-1, 1, -1, 1, -1, NaN]));
});

// The checks the integration tests apply after every frame must be able to fail: each problem
// kind is found in a mesh made to have it, and the tests' reading of expressions agrees with the
// server's (`isomesh eval`).
import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { join } from 'node:path';
import { test } from 'node:test';
import { promisify } from 'node:util';

import { SessionMesh } from '../../../clients/js/src/index.js';
import { BIN_DIR, CheckedMesh } from './harness.js';
import { compileSurface, valueAndGradient } from './surface.js';

// The octahedron |x|+|y|+|z| = 1 inscribed in the unit sphere: six vertices, eight triangles,
// counter-clockwise seen from outside (f > 0 for x^2+y^2+z^2=1).
const VERTICES = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
const FACES = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
const SPHERE = { version: 1, expression: 'x^2+y^2+z^2=1', parameters: {}, box: [-2, 2, -2, 2, -2, 2] };

/** A keyframe object as decodeFrame returns it, for `faces` over `vertices`. */
function keyframe(faces = FACES, vertices = VERTICES) {
  return {
    header: { kind: 'keyframe', sequence: 0, functionVersion: 1 },
    removed: [],
    triangleIds: faces.map((_, i) => i),
    mesh: {
      pointCount: vertices.length,
      globalIds: Uint32Array.from(vertices.map((_, i) => 100 + i)),
      positions: Float32Array.from(vertices.flat()),
      normals: Float32Array.from(vertices.flat()),
      faces: Uint32Array.from(faces.flat()),
    },
  };
}

function problems(frame, state = SPHERE) {
  const mesh = new SessionMesh();
  assert.equal(mesh.apply(frame), 'applied');
  return new CheckedMesh(mesh).check(frame, state).map((p) => p.kind).sort();
}

test('CheckedMesh finds nothing wrong with a closed, outward, on-surface mesh', () => {
  assert.deepEqual(problems(keyframe()), []);
});

test('CheckedMesh finds holes, folds, reversed triangles, zero areas and stray vertices', () => {
  assert.deepEqual(problems(keyframe(FACES.slice(1))), ['open']);
  const flipped = FACES.map((f, i) => (i === 0 ? [f[0], f[2], f[1]] : f));
  assert.deepEqual(problems(keyframe(flipped)), ['non_manifold', 'reversed']);
  const inward = FACES.map(([a, b, c]) => [a, c, b]);
  assert.deepEqual(problems(keyframe(inward)), ['reversed']);
  const squashed = VERTICES.map((v, i) => (i === 4 ? [0, 0, 0] : v));
  assert.deepEqual(problems(keyframe(FACES, squashed)), ['off_surface']);
  const flat = VERTICES.map((v, i) => (i === 4 ? [0.5, 0.5, 0] : v)); // on the edge 0-2
  assert.ok(problems(keyframe(FACES, flat)).includes('zero_area'));
});

test('CheckedMesh lets an open edge on the box boundary be (a surface the box cuts)', () => {
  const inBox = { ...SPHERE, box: [-1, 1, -1, 1, -1, 1] };
  assert.deepEqual(problems(keyframe(FACES.slice(1)), inBox), []);
});

test('the tests read expressions as the server does (isomesh eval)', async () => {
  const cases = [
    ['x^2+y^2+z^2+2cos(2x)=5', {}],
    ['(sqrt(x^2+y^2)-1.8)^2+z^2=0.5', {}],
    ['x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0', {}],
    ['10x^2+y^2+z^2=5', {}],
    ['sqrt(x^2+y^2+z^2)=2', {}],
    ['x^2+y^2+z^2=a', { a: 4.5 }],
    ['-x^2+2x y-2x+e^z-pi', {}],
  ];
  for (const [expression, parameters] of cases) {
    const args = ['eval', expression, '--at', '0.3,-1.2,0.7', ...Object.entries(parameters).flatMap(([k, v]) => ['--param', `${k}=${v}`])];
    const { stdout } = await promisify(execFile)(join(BIN_DIR, 'isomesh'), args);
    const expected = JSON.parse(stdout).value;
    const { value } = valueAndGradient(compileSurface(expression), 0.3, -1.2, 0.7, parameters);
    assert.ok(Math.abs(value - expected) <= 1e-9 * Math.max(1, Math.abs(expected)), `${expression}: ${value} vs ${expected}`);
  }
});

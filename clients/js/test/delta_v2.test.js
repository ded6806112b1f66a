// Version-2 deltas (PROTOCOL.md 4.5): the worked delta of 4.5.4 decoded against the octahedron,
// the range decoder's integer codes, and deltas that do not fit the held mesh.

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { decodeDeltaV2 } from '../src/delta_v2.js';
import { GridMath } from '../src/delta_v2_geometry.js';
import { decodeFrame } from '../src/frame.js';
import { HeldMesh } from '../src/held_mesh.js';
import { RangeDecoder, intModel } from '../src/range_decoder.js';

const GRID = { origin: [-1.03125, -1.03125, -1.03125], range: 2.0625, positionBits: 14, normalBits: 10 };
const math = new GridMath(GRID);

/** The octahedron of 4.5.4: vertices 0 ... 5 at +-1 on the axes, triangles 0 ... 7. */
function octahedron() {
  const corners = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
  const grid = (c) => c.map((x) => (x === 1 ? 16135 : x === -1 ? 248 : 8192));
  const faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
  const positions = new Float32Array(corners.flatMap((c) => math.dequantize(grid(c))));
  const normals = new Float32Array(corners.flatMap((c) => math.decodeNormal(math.encodeNormal(c))));
  const held = new HeldMesh();
  held.apply({
    header: { kind: 'keyframe' },
    removed: [],
    triangleIds: faces.map((_, t) => t),
    mesh: { globalIds: Uint32Array.from([0, 1, 2, 3, 4, 5]), positions, normals, faces: Uint32Array.from(faces.flat()) },
  });
  return held;
}

/** The bytes between the example-frame-v2 (or `name`) markers of PROTOCOL.md. */
function exampleFrame(name = 'example-frame-v2') {
  const doc = readFileSync(fileURLToPath(new URL('../../../protocol/PROTOCOL.md', import.meta.url)), 'utf8');
  const block = doc.split(`<!-- ${name} -->`)[1].split(`<!-- /${name} -->`)[0];
  return Uint8Array.from(block.replace(/```/g, '').trim().split(/\s+/), (h) => parseInt(h, 16));
}

test('decodeDeltaV2 (the worked delta of PROTOCOL.md 4.5.4)', () => {
  const bytes = exampleFrame();
  assert.equal(bytes.length, 68);
  const frame = decodeFrame(bytes, null);
  assert.deepEqual(
    [frame.header.version, frame.header.kind, frame.header.sequence, frame.header.baseTriangleId, frame.header.baseVertexId],
    [2, 'delta', 1, 8, 6],
  );
  const held = octahedron();
  const decoded = decodeDeltaV2(frame.header, frame.body, held, GRID);
  assert.deepEqual(decoded.removed, [0, 4]);
  assert.deepEqual(decoded.triangleIds, [8, 9, 10, 11]);
  const corners = (t) => [0, 1, 2].map((k) => decoded.mesh.globalIds[decoded.mesh.faces[3 * t + k]]);
  assert.deepEqual([0, 1, 2, 3].map(corners), [[0, 6, 4], [6, 2, 4], [2, 6, 5], [6, 0, 5]]);
  const p = decoded.mesh.globalIds.indexOf(6);
  assert.deepEqual(math.recover(decoded.mesh.positions.subarray(3 * p, 3 * p + 3)), [13752, 13752, 8192]);
  assert.deepEqual(math.encodeNormal(decoded.mesh.normals.subarray(3 * p, 3 * p + 3)), [256, 256]);
  // Applied, the held mesh is the split octahedron: 10 triangles, 7 vertices.
  held.apply(decoded);
  assert.deepEqual([held.triangles.size, held.vertices.size], [10, 7]);
});

test('decodeDeltaV2 (the worked move of PROTOCOL.md 4.5.5)', () => {
  const bytes = exampleFrame('example-frame-v2-move');
  assert.equal(bytes.length, 68);
  const frame = decodeFrame(bytes, null);
  const decoded = decodeDeltaV2(frame.header, frame.body, octahedron(), GRID);
  assert.deepEqual([decoded.removed, decoded.triangleIds, decoded.moved], [[], [], [0, 1, 2, 3, 4, 5]]);
  // Every vertex from grid point 16135 (+1) to 16373 (+1.03), or from 248 (-1) to 10 (-1.03).
  const moved = (x) => (x === 16135 ? 16373 : x === 248 ? 10 : x);
  const before = octahedron();
  decoded.mesh.globalIds.forEach((id, p) => {
    const expected = math.recover(before.vertex(id).position).map(moved);
    assert.deepEqual(math.recover(decoded.mesh.positions.subarray(3 * p, 3 * p + 3)), expected, `vertex ${id}`);
  });
});

test('GridMath::predictSplit (the prediction of 4.5.4)', () => {
  const held = octahedron();
  const [a, b] = [held.vertex(0), held.vertex(2)];
  assert.deepEqual([math.recover(a.position), math.recover(b.position)], [[16135, 8192, 8192], [8192, 16135, 8192]]);
  assert.deepEqual(math.predictSplit(math.recover(a.position), math.recover(b.position), a.normal, b.normal), [13156, 13156, 8192]);
  assert.deepEqual(math.predictNormal(a.normal, b.normal), [256, 256]);
});

test('decodeDeltaV2 (a delta that does not fit the held mesh is bad_frame)', () => {
  const frame = decodeFrame(exampleFrame(), null);
  const held = octahedron();
  held.apply({ header: { kind: 'delta' }, removed: [0], triangleIds: [], mesh: null });
  assert.throws(() => decodeDeltaV2(frame.header, frame.body, held, GRID), { code: 'bad_frame' });
});

test('RangeDecoder (bodies shorter than 5 bytes, not starting with 0, or read far past their end)', () => {
  assert.throws(() => new RangeDecoder(Uint8Array.of(0, 0, 0, 0)), { code: 'bad_frame' });
  assert.throws(() => new RangeDecoder(Uint8Array.of(1, 0, 0, 0, 0)), { code: 'bad_frame' });
  const coder = new RangeDecoder(Uint8Array.of(0, 0xff, 0xff, 0xff, 0xff));
  assert.throws(() => {
    for (let i = 0; i < 100; ++i) coder.uint(intModel());
  }, { code: 'bad_frame' });
});

test('decodeFrame (a truncated version-2 delta header is bad_frame)', () => {
  assert.throws(() => decodeFrame(exampleFrame().subarray(0, 40), null), { code: 'bad_frame' });
});

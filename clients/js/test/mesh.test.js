import assert from 'node:assert/strict';
import { test } from 'node:test';

import { decodeFrame } from '../src/frame.js';
import { Outcome, SessionMesh } from '../src/mesh.js';
import { FakeMeshDecoder, buildFrame, vertex } from './support.js';

const decoder = new FakeMeshDecoder();
const frame = (options) => decodeFrame(buildFrame(options), decoder);

// A square (triangles 10, 11 over vertices 1-4), then a split of triangle 11 into 100, 101 by a
// new vertex 5.
const keyframe = (sequence = 0) =>
  frame({
    kind: 'keyframe',
    sequence,
    triangleIds: [10, 11],
    mesh: { vertices: [1, 2, 3, 4].map((id) => vertex(id)), triangles: [[1, 2, 3], [1, 3, 4]] },
  });
const split = (sequence = 1) =>
  frame({
    sequence,
    removed: [11],
    baseTriangleId: 100,
    mesh: { vertices: [1, 3, 4, 5].map((id) => vertex(id)), triangles: [[1, 3, 5], [1, 5, 4]] },
  });

/** The corner positions the slot table holds for triangle `id`. */
function corners(mesh, id) {
  const s = mesh.slots.slotOf(id);
  return Array.from(mesh.slots.positions.subarray(9 * s, 9 * s + 9));
}

test('SessionMesh: a keyframe, then a delta with the next sequence number', () => {
  const mesh = new SessionMesh({ initialCapacity: 2 });
  assert.equal(mesh.apply(keyframe()), Outcome.applied);
  assert.equal(mesh.triangleCount, 2);
  assert.equal(mesh.apply(split()), Outcome.applied);
  assert.deepEqual(mesh.sortedTriangles(), [
    { id: 10, vertices: [1, 2, 3] },
    { id: 100, vertices: [1, 3, 5] },
    { id: 101, vertices: [1, 5, 4] },
  ]);
  assert.deepEqual(corners(mesh, 101), [...vertex(1).slice(1, 4), ...vertex(5).slice(1, 4), ...vertex(4).slice(1, 4)]);
  assert.equal(mesh.sequence, 1);
  assert.deepEqual([...mesh.vertices.keys()].sort(), [1, 2, 3, 4, 5]);
  mesh.slots.checkInvariants();
});

test('SessionMesh: unused vertices are dropped', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe());
  mesh.apply(frame({ sequence: 1, removed: [10] }));
  assert.deepEqual([...mesh.vertices.keys()].sort(), [1, 3, 4]);
  assert.equal(mesh.vertices.get(1).uses, 1);
});

test('SessionMesh: deltas before any keyframe wait for one', () => {
  const mesh = new SessionMesh();
  assert.equal(mesh.apply(split()), Outcome.awaitingKeyframe);
  assert.equal(mesh.triangleCount, 0);
});

test('SessionMesh: stale deltas are skipped, a gap stops the mesh until a keyframe', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe(5));
  assert.equal(mesh.apply(split(5)), Outcome.stale);
  assert.equal(mesh.apply(split(7)), Outcome.gap);
  assert.equal(mesh.synchronized, false);
  assert.equal(mesh.apply(split(8)), Outcome.awaitingKeyframe);
  assert.equal(mesh.apply(keyframe(8)), Outcome.applied);
  assert.equal(mesh.apply(split(9)), Outcome.applied);
});

test('SessionMesh: an inconsistent delta changes nothing and needs a keyframe', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe());
  const before = mesh.sortedTriangles();
  const unknownRemoval = frame({ sequence: 1, removed: [11, 12] });
  assert.equal(mesh.apply(unknownRemoval), Outcome.inconsistent);
  assert.deepEqual(mesh.sortedTriangles(), before);

  mesh.apply(keyframe(1));
  const known = frame({ sequence: 2, baseTriangleId: 10, mesh: { vertices: [1, 2, 4].map((id) => vertex(id)), triangles: [[1, 2, 4]] } });
  assert.equal(mesh.apply(known), Outcome.inconsistent, 're-adding a live id');
  assert.deepEqual(mesh.sortedTriangles(), before);
});

test('SessionMesh: a delta may re-add an id it removes', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe());
  const replace = frame({ sequence: 1, removed: [11], baseTriangleId: 11, mesh: { vertices: [1, 3, 4].map((id) => vertex(id)), triangles: [[4, 1, 3]] } });
  assert.equal(mesh.apply(replace), Outcome.applied);
  assert.deepEqual(mesh.sortedTriangles()[1], { id: 11, vertices: [4, 1, 3] });
});

test('SessionMesh: a known vertex sent with new values moves in every triangle using it', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe());
  const moved = frame({ sequence: 1, baseTriangleId: 200, mesh: { vertices: [vertex(3, 0.25), vertex(4), vertex(6)], triangles: [[3, 6, 4]] } });
  assert.equal(mesh.apply(moved), Outcome.applied);
  const x3 = vertex(3, 0.25)[1];
  assert.equal(corners(mesh, 10)[6], x3, 'triangle 10 (corner 2 is vertex 3)');
  assert.equal(corners(mesh, 11)[3], x3, 'triangle 11 (corner 1 is vertex 3)');
  assert.deepEqual(mesh.vertices.get(3).position, [x3, 6, -3]);
});

test('SessionMesh: toIndexed welds corners by vertex id', () => {
  const mesh = new SessionMesh();
  mesh.apply(keyframe());
  const indexed = mesh.toIndexed();
  assert.deepEqual([...indexed.vertexIds], [1, 2, 3, 4]);
  assert.equal(indexed.indices.length, 6);
  const tri = (t) => [...indexed.indices.subarray(3 * t, 3 * t + 3)].map((i) => indexed.vertexIds[i]);
  assert.deepEqual([tri(0), tri(1)].sort(), [[1, 2, 3], [1, 3, 4]]);
});

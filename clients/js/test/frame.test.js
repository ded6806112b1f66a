import assert from 'node:assert/strict';
import { test } from 'node:test';

import { decodeFrame, readFrameHeader } from '../src/frame.js';
import { FakeMeshDecoder, SESSION, buildFrame, vertex } from './support.js';

const decoder = new FakeMeshDecoder();
const square = { vertices: [1, 2, 3, 4].map((id) => vertex(id)), triangles: [[1, 2, 3], [1, 3, 4]] };
const badFrame = (pattern) => (e) => e.code === 'bad_frame' && pattern.test(e.message);

test('readFrameHeader reads every field little endian', () => {
  const bytes = buildFrame({ kind: 'delta', flags: 3, sequence: 2 ** 40 + 5, baseTriangleId: 77, functionVersion: 9, removed: [4, 6], mesh: square });
  const h = readFrameHeader(bytes);
  assert.equal(h.kind, 'delta');
  assert.equal(h.converged, true);
  assert.equal(h.catchUp, true);
  assert.equal(h.session, SESSION);
  assert.equal(h.sequence, 2 ** 40 + 5);
  assert.equal(h.timestampUs, 1_700_000_000_000_000);
  assert.equal(h.baseTriangleId, 77);
  assert.equal(h.functionVersion, 9);
  assert.equal(h.removedCount, 2);
  assert.equal(h.triangleCount, 2);
  assert.equal(h.pointCount, 4);
});

test('decodeFrame: delta triangles get base id + decoded index', () => {
  const frame = decodeFrame(buildFrame({ baseTriangleId: 500, removed: [3, 9, 10], mesh: square }), decoder);
  assert.deepEqual(frame.removed, [3, 9, 10]);
  assert.deepEqual(frame.triangleIds, [500, 501]);
  assert.deepEqual([...frame.mesh.globalIds], [1, 2, 3, 4]);
});

test('decodeFrame: keyframe triangles take their explicit ids', () => {
  const frame = decodeFrame(buildFrame({ kind: 'keyframe', triangleIds: [42, 7], mesh: square }), decoder);
  assert.deepEqual(frame.triangleIds, [42, 7]);
});

test('decodeFrame: a delta that only removes has no mesh', () => {
  const frame = decodeFrame(buildFrame({ removed: [1, 2] }), decoder);
  assert.equal(frame.mesh, null);
  assert.deepEqual(frame.triangleIds, []);
});

test('readFrameHeader rejects malformed headers', () => {
  const good = buildFrame({ mesh: square });
  assert.throws(() => readFrameHeader(good.subarray(0, 75)), badFrame(/shorter/));
  const corrupt = (offset, value) => {
    const bytes = good.slice();
    bytes[offset] = value;
    return bytes;
  };
  assert.throws(() => readFrameHeader(corrupt(0, 0x41)), badFrame(/ISOM/));
  assert.throws(() => readFrameHeader(corrupt(4, 3)), (e) => e.code === 'unsupported_version');
  assert.throws(() => readFrameHeader(corrupt(5, 3)), badFrame(/kind/));
  assert.throws(() => readFrameHeader(buildFrame({ functionVersion: 0 })), badFrame(/version 0/));
  assert.throws(() => readFrameHeader(buildFrame({ kind: 'keyframe', removed: [1] })), badFrame(/removes nothing/));
  assert.throws(() => readFrameHeader(buildFrame({ override: { removedCount: 2 ** 22 + 1 } })), badFrame(/2\^22/));
  assert.throws(() => readFrameHeader(buildFrame({ mesh: square, override: { meshBytes: 0 } })), badFrame(/payload length/));
  assert.throws(() => readFrameHeader(buildFrame({ mesh: square, override: { pointCount: 7 } })), badFrame(/point count/));
  assert.throws(() => readFrameHeader(buildFrame({ mesh: square, baseTriangleId: Number.MAX_SAFE_INTEGER })), badFrame(/2\^53/));
  assert.throws(() => readFrameHeader(buildFrame({ sequence: 2 ** 53 })), badFrame(/sequence/));
});

test('decodeFrame rejects inconsistent sections and payloads', () => {
  const longer = buildFrame({ mesh: square });
  assert.throws(() => decodeFrame(longer.subarray(0, longer.length - 1), decoder), badFrame(/header says/));
  assert.throws(() => decodeFrame(buildFrame({ removed: [1, 2], override: { removedCount: 3 } }), decoder), badFrame(/truncated/));
  assert.throws(() => decodeFrame(buildFrame({ kind: 'keyframe', triangleIds: [5, 5], mesh: square }), decoder), badFrame(/repeat/));
  const welded = { vertices: [vertex(1), vertex(2), vertex(3), vertex(1, 0.5)], triangles: [[1, 2, 3], [3, 2, 1]] };
  assert.throws(() => decodeFrame(buildFrame({ mesh: welded }), decoder), badFrame(/two different values/));
  const degenerate = { vertices: [vertex(1), vertex(2)], triangles: [[1, 2, 1]] };
  assert.throws(() => decodeFrame(buildFrame({ mesh: degenerate }), decoder), badFrame(/repeats a vertex/));
  assert.throws(() => decodeFrame(buildFrame({ mesh: square, override: { pointCount: 3 } }), decoder), badFrame(/counts disagree/));
});

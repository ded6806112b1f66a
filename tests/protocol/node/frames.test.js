// Decodes frames written by the C++ protocol library with draco3d and a reader written from
// PROTOCOL.md, and checks it reads exactly what the C++ decoder read.
// The C++ tool: $ISOMESH_PROTOCOL_SAMPLE, default build/bin/isomesh-protocol-sample.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import draco3d from 'draco3d';

import { canonical, decodeFrame, decodeMeshPayload, readHeader, Replica } from './frame.js';

const here = path.dirname(fileURLToPath(import.meta.url));
const tool =
  process.env.ISOMESH_PROTOCOL_SAMPLE ?? path.resolve(here, '../../../build/bin/isomesh-protocol-sample');

let draco;
let dir;
let manifest;
const frameBytes = (name) => new Uint8Array(fs.readFileSync(path.join(dir, name)));

before(async () => {
  draco = await draco3d.createDecoderModule({});
  dir = fs.mkdtempSync(path.join(os.tmpdir(), 'isomesh-frames-'));
  execFileSync(tool, ['frames', dir]);
  manifest = JSON.parse(fs.readFileSync(path.join(dir, 'frames.json'), 'utf8'));
});

test('the sample session has a keyframe, deltas, a function change and a converged removal', () => {
  const kinds = manifest.frames.map((f) => f.kind);
  assert.deepEqual(kinds, ['keyframe', 'delta', 'delta', 'delta', 'delta', 'delta']);
  assert.equal(manifest.frames[4].function_version, 2);
  assert.equal(manifest.frames.at(-1).flags & 1, 1);
});

test('headers read as the C++ decoder read them', () => {
  for (const expected of manifest.frames) {
    const header = readHeader(frameBytes(expected.file));
    for (const field of ['kind', 'flags', 'session', 'sequence', 'timestamp_us', 'function_version']) {
      assert.equal(header[field], expected[field], `${expected.file} ${field}`);
    }
  }
});

test('the global id attribute is found by metadata and has unique id 2', () => {
  const bytes = frameBytes(manifest.frames[1].file);
  const header = readHeader(bytes);
  const payload = decodeMeshPayload(draco, bytes.subarray(bytes.length - header.mesh_bytes));
  assert.equal(payload.uniqueIdOfGlobalId, 2);
  assert.equal(payload.pointCount, header.point_count);
});

test('every frame decodes to the same removed ids, triangles and vertex bits', () => {
  for (const expected of manifest.frames) {
    const frame = decodeFrame(draco, frameBytes(expected.file));
    assert.deepEqual(frame.removed, expected.removed, `${expected.file} removed`);
    const triangles = frame.triangles.map((t) => [t.id, ...t.vertices]);
    assert.deepEqual(triangles, expected.triangles, `${expected.file} triangles`);
    const vertices = expected.vertices.map(([id]) => {
      const v = frame.vertices.get(id);
      assert.ok(v, `${expected.file} lacks vertex ${id}`);
      return [id, ...v.position, ...v.normal];
    });
    assert.deepEqual(vertices, expected.vertices, `${expected.file} vertices`);
    assert.equal(frame.vertices.size, expected.vertices.length);
  }
});

test('applying the frames in order gives the final mesh', () => {
  const replica = new Replica();
  for (const { file } of manifest.frames) {
    assert.equal(replica.apply(decodeFrame(draco, frameBytes(file))), 'applied', file);
  }
  const mesh = [...replica.triangles]
    .map(([id, vertices]) => [id, ...canonical(vertices)])
    .sort((a, b) => a[0] - b[0]);
  assert.deepEqual(mesh, manifest.final_triangles);
  const used = new Set([...replica.triangles.values()].flat());
  const vertices = [...used]
    .sort((a, b) => a - b)
    .map((id) => [id, ...replica.vertices.get(id).position, ...replica.vertices.get(id).normal]);
  assert.deepEqual(vertices, manifest.final_vertices);
});

test('a skipped delta is detected as a gap', () => {
  const replica = new Replica();
  const frames = manifest.frames.map(({ file }) => decodeFrame(draco, frameBytes(file)));
  assert.equal(replica.apply(frames[0]), 'applied');
  assert.equal(replica.apply(frames[2]), 'gap');
  assert.equal(replica.apply(frames[3]), 'awaiting_keyframe');
  assert.equal(replica.apply(frames[0]), 'applied');
  assert.equal(replica.apply(frames[0]), 'applied');
  assert.equal(replica.apply(frames[1]), 'applied');
  assert.equal(replica.apply(frames[1]), 'stale');
});

test('truncated frames are rejected', () => {
  const bytes = frameBytes(manifest.frames[1].file);
  for (const length of [0, 40, 75, 76, bytes.length - 1]) {
    assert.throws(() => decodeFrame(draco, bytes.subarray(0, length)), /bad frame/, `length ${length}`);
  }
});

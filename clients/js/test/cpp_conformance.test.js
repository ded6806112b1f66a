// The library against the C++ protocol library: frames written by isomesh-protocol-sample (a
// keyframe and deltas of a refining sphere, real Draco payloads) must decode to exactly what the
// C++ decoder reads from them, and applying them must end with the sender's mesh.
//
// The sample tool is built with the project (build/bin); ISOMESH_PROTOCOL_SAMPLE overrides its
// path. Without it the test is skipped, saying so.

import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { decodeFrame } from '../src/frame.js';
import { loadDracoDecoder } from '../src/draco_loader.js';
import { Outcome, SessionMesh } from '../src/mesh.js';

const repo = fileURLToPath(new URL('../../..', import.meta.url));
const tool = process.env.ISOMESH_PROTOCOL_SAMPLE ?? join(repo, 'build/bin/isomesh-protocol-sample');

test('frames of the C++ encoder decode as the C++ decoder reads them', { skip: !existsSync(tool) && `no ${tool}` }, async (t) => {
  const dir = mkdtempSync(join(tmpdir(), 'isomesh-js-sample-'));
  t.after(() => rmSync(dir, { recursive: true, force: true }));
  execFileSync(tool, ['frames', dir], { stdio: 'pipe' });
  const manifest = JSON.parse(readFileSync(join(dir, 'frames.json'), 'utf8'));
  const decoder = await loadDracoDecoder();
  const mesh = new SessionMesh();
  for (const expected of manifest.frames) {
    const frame = decodeFrame(new Uint8Array(readFileSync(join(dir, expected.file))), decoder);
    const h = frame.header;
    assert.deepEqual(
      [h.kind, h.flags, h.session, h.sequence, h.timestampUs, h.functionVersion],
      [expected.kind, expected.flags, expected.session, expected.sequence, expected.timestamp_us, expected.function_version],
      expected.file,
    );
    assert.deepEqual(frame.removed, expected.removed, `${expected.file}: removed ids`);
    assert.deepEqual(weldedVertices(frame), expected.vertices, `${expected.file}: vertices`);
    const triangles = frame.triangleIds.map((id, t) => [id, ...[0, 1, 2].map((k) => frame.mesh.globalIds[frame.mesh.faces[3 * t + k]])]);
    assert.deepEqual(triangles, expected.triangles, `${expected.file}: triangles`);
    assert.equal(mesh.apply(frame), Outcome.applied);
  }
  // Draco may hand a triangle's corners back rotated (abc as bca, never mirrored): compare the
  // final mesh with the sender's up to rotation.
  const final = mesh.sortedTriangles().map((t) => [t.id, ...t.vertices]);
  assert.deepEqual(final.map(rotatedToSmallest), manifest.final_triangles.map(rotatedToSmallest));
  mesh.slots.checkInvariants();
  decoder.dispose();
});

function rotatedToSmallest([id, a, b, c]) {
  if (a < b && a < c) return [id, a, b, c];
  return b < c ? [id, b, c, a] : [id, c, a, b];
}

/** [id, x, y, z, nx, ny, nz] per distinct global id, in order of first use, as the C++ decoder lists them. */
function weldedVertices(frame) {
  if (!frame.mesh) return [];
  const { globalIds, positions, normals } = frame.mesh;
  const seen = new Set();
  const out = [];
  for (let p = 0; p < globalIds.length; ++p) {
    if (seen.has(globalIds[p])) continue;
    seen.add(globalIds[p]);
    out.push([globalIds[p], ...positions.subarray(3 * p, 3 * p + 3), ...normals.subarray(3 * p, 3 * p + 3)]);
  }
  return out;
}

test('version-2 frames of the C++ encoder decode bit for bit as the C++ decoder reads them', { skip: !existsSync(tool) && `no ${tool}` }, async (t) => {
  const dir = mkdtempSync(join(tmpdir(), 'isomesh-js-sample-v2-'));
  t.after(() => rmSync(dir, { recursive: true, force: true }));
  execFileSync(tool, ['frames-v2', dir], { stdio: 'pipe' });
  const manifest = JSON.parse(readFileSync(join(dir, 'frames.json'), 'utf8'));
  const decoder = await loadDracoDecoder();
  const mesh = new SessionMesh();
  const byId = (a, b) => a[0] - b[0];
  for (const expected of manifest.frames) {
    const frame = decodeFrame(new Uint8Array(readFileSync(join(dir, expected.file))), decoder);
    assert.equal(frame.header.version, 2);
    assert.equal(mesh.apply(frame), Outcome.applied, `${expected.file}: ${frame.error?.message}`);
    const h = frame.header;
    assert.deepEqual(
      [h.kind, h.flags, h.session, h.sequence, h.timestampUs, h.functionVersion],
      [expected.kind, expected.flags, expected.session, expected.sequence, expected.timestamp_us, expected.function_version],
      expected.file,
    );
    assert.deepEqual(frame.removed, expected.removed, `${expected.file}: removed ids`);
    // Every value bit-equal to the C++ decoder's (float32 values, compared as numbers).
    assert.deepEqual(weldedVertices(frame).sort(byId), [...expected.vertices].sort(byId), `${expected.file}: vertices`);
    const triangles = frame.triangleIds.map((id, i) => [id, ...[0, 1, 2].map((k) => frame.mesh.globalIds[frame.mesh.faces[3 * i + k]])]);
    assert.deepEqual(triangles.map(rotatedToSmallest).sort(byId), expected.triangles.map(rotatedToSmallest).sort(byId), `${expected.file}: triangles`);
  }
  const final = mesh.sortedTriangles().map((t) => [t.id, ...t.vertices]);
  assert.deepEqual(final.map(rotatedToSmallest), manifest.final_triangles.map(rotatedToSmallest));
  assert.deepEqual(
    [...mesh.held.triangles].map(([id, c]) => [id, ...c]).sort(byId).map(rotatedToSmallest),
    manifest.final_triangles.map(rotatedToSmallest),
  );
  mesh.slots.checkInvariants();
  decoder.dispose();
});

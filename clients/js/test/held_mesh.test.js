// The held mesh of version-2 sessions (typed arrays, stars threaded through the corners) and the
// in-place decoding of deltas on it, on the frames of the C++ encoder (isomesh-protocol-sample,
// built with the project; ISOMESH_PROTOCOL_SAMPLE overrides its path; without it these are
// skipped, saying so): decoding in place must equal decoding on the side then applying, and a
// delta that turns out malformed, wherever it breaks, must leave the held mesh as it was.

import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { applyDeltaV2, decodeDeltaV2 } from '../src/delta_v2.js';
import { loadDracoDecoder } from '../src/draco_loader.js';
import { GridMath } from '../src/delta_v2_geometry.js';
import { decodeFrame } from '../src/frame.js';
import { HeldMesh } from '../src/held_mesh.js';
import { Outcome, SessionMesh } from '../src/mesh.js';
import { movesDelta } from './delta_v2_writer.js';

const repo = fileURLToPath(new URL('../../..', import.meta.url));
const tool = process.env.ISOMESH_PROTOCOL_SAMPLE ?? join(repo, 'build/bin/isomesh-protocol-sample');
const skip = !existsSync(tool) && `no ${tool}`;

/** The version-2 sample session's frames, decoded as far as decodeFrame goes. */
async function sampleFrames(t) {
  const dir = mkdtempSync(join(tmpdir(), 'isomesh-js-held-'));
  t.after(() => rmSync(dir, { recursive: true, force: true }));
  execFileSync(tool, ['frames-v2', dir], { stdio: 'pipe' });
  const manifest = JSON.parse(readFileSync(join(dir, 'frames.json'), 'utf8'));
  const decoder = await loadDracoDecoder();
  t.after(() => decoder.dispose());
  return manifest.frames.map(({ file }) => {
    const bytes = new Uint8Array(readFileSync(join(dir, file)));
    return { bytes, frame: decodeFrame(bytes, decoder) };
  });
}

/**
 * Everything a held mesh says, in a canonical order: triangles with corners, vertices with
 * values, and each vertex's star (sorted), which must be exactly the triangles using it.
 */
function snapshot(held) {
  const byId = (a, b) => a[0] - b[0];
  const triangles = [...held.triangles].map(([id, c]) => [id, ...c]).sort(byId);
  const vertices = [...held.vertices].map(([id, v]) => [id, ...v.position, ...v.normal]).sort(byId);
  const stars = vertices.map(([id]) => [id, ...held.star(id).sort((a, b) => a - b)]);
  const using = new Map(vertices.map(([id]) => [id, []]));
  for (const [id, ...c] of triangles) for (const v of c) using.get(v).push(id);
  assert.deepEqual(stars, [...using].map(([id, list]) => [id, ...list]), 'stars name exactly the triangles using each vertex');
  assert.deepEqual([held.triangles.size, held.vertices.size], [triangles.length, vertices.length]);
  return { triangles, vertices };
}

/** Two held meshes after the sample's keyframe, and its grid. */
function heldPair(frames) {
  const [{ frame: keyframe }] = frames;
  const inPlace = new HeldMesh(16); // small: the arrays and indexes grow while deltas apply
  const reference = new HeldMesh(16);
  inPlace.apply(keyframe);
  reference.apply(keyframe);
  return { inPlace, reference, grid: keyframe.header.grid };
}

test('applyDeltaV2 (in place equals decodeDeltaV2 then HeldMesh::apply; decodeDeltaV2 leaves the held mesh as it was)', { skip }, async (t) => {
  const frames = await sampleFrames(t);
  const { inPlace, reference, grid } = heldPair(frames);
  for (const { frame } of frames.slice(1)) {
    const before = snapshot(reference);
    const decoded = decodeDeltaV2(frame.header, frame.body, reference, grid);
    assert.deepEqual(snapshot(reference), before, 'decodeDeltaV2 changed the held mesh');
    reference.apply(decoded);
    assert.deepEqual(applyDeltaV2(frame.header, frame.body, inPlace, grid), decoded);
    assert.deepEqual(snapshot(inPlace), snapshot(reference));
  }
});

test('applyDeltaV2 (a delta made malformed at any byte leaves the held mesh as it was)', { skip }, async (t) => {
  const frames = await sampleFrames(t);
  const { inPlace, grid } = heldPair(frames);
  const late = new Set(); // errors found after the body's splits changed the mesh
  for (const { bytes, frame } of frames.slice(1)) {
    const before = snapshot(inPlace);
    for (let at = 56; at < bytes.length; ++at) {
      for (const value of [0x00, 0x5a, 0xff]) {
        const broken = bytes.slice();
        broken[at] = value;
        const { header, body } = decodeFrame(broken, null);
        try {
          applyDeltaV2(header, body, inPlace, grid);
        } catch (error) {
          assert.equal(error.code, 'bad_frame');
          assert.deepEqual(snapshot(inPlace), before, `byte ${at} = ${value}: ${error.message}`);
          if (/^(removes|moves|a triangle)/.test(error.message)) late.add(error.message.split(' ')[0]);
          continue;
        }
        // It still decoded (to something else): start again from the mesh before it.
        inPlace.apply({ header: { kind: 'keyframe' }, ...heldContent(before) });
      }
    }
    applyDeltaV2(frame.header, frame.body, inPlace, grid);
  }
  assert.ok(late.size > 0, 'no mutation failed after changes were made: the rollback went untested');
});

/** A snapshot as the content of a keyframe (HeldMesh::apply). */
function heldContent({ triangles, vertices }) {
  const point = new Map(vertices.map(([id], p) => [id, p]));
  return {
    removed: [],
    triangleIds: triangles.map(([id]) => id),
    mesh: {
      globalIds: Uint32Array.from(vertices, ([id]) => id),
      positions: Float32Array.from(vertices.flatMap((v) => v.slice(1, 4))),
      normals: Float32Array.from(vertices.flatMap((v) => v.slice(4, 7))),
      faces: Uint32Array.from(triangles.flatMap((c) => c.slice(1).map((v) => point.get(v)))),
    },
  };
}

test('SessionMesh (a version-2 move rewrites every corner of the moved vertices, their triangles kept)', { skip }, async (t) => {
  const frames = await sampleFrames(t);
  const mesh = new SessionMesh({ initialCapacity: 4 });
  for (const { frame } of frames) assert.equal(mesh.apply(frame), Outcome.applied);
  const math = new GridMath(mesh.grid);
  const ids = [...mesh.vertices.keys()].sort((a, b) => a - b).filter((_, i) => i % 3 === 0);
  const moves = ids.map((id) => {
    const code = math.encodeNormal(mesh.vertices.get(id).normal);
    return { id, position: [2, -1, 3], normal: code.map((c) => (c < math.maxOctahedral ? 1 : -1)) };
  });
  const expected = new Map(moves.map(({ id, position, normal }) => {
    const v = mesh.vertices.get(id);
    const q = math.recover(v.position).map((c, axis) => c + position[axis]);
    const n = math.encodeNormal(v.normal).map((c, k) => c + normal[k]);
    return [id, { position: math.dequantize(q), normal: math.decodeNormal(n) }];
  }));
  const triangles = mesh.sortedTriangles();
  const last = frames.at(-1).frame.header;
  const bytes = movesDelta({ sequence: last.sequence + 1, baseTriangleId: 1e6, baseVertexId: 1e6, functionVersion: last.functionVersion, moves });
  const frame = decodeFrame(bytes, null);
  assert.equal(mesh.apply(frame), Outcome.applied, frame.error?.message);
  assert.deepEqual([frame.removed, frame.triangleIds, frame.mesh.pointCount], [[], [], moves.length]);
  assert.deepEqual(mesh.sortedTriangles(), triangles, 'a move keeps every triangle');
  const { slots, vertices } = mesh;
  for (let c = 0; c < 3 * slots.count; ++c) {
    const id = slots.vertexIds[c];
    const v = vertices.get(id);
    if (expected.has(id)) assert.deepEqual([v.position, v.normal], [expected.get(id).position, expected.get(id).normal]);
    const held = mesh.held.vertex(id);
    assert.deepEqual([held.position, held.normal], [v.position, v.normal]);
    assert.deepEqual(Array.from(slots.positions.subarray(3 * c, 3 * c + 3)), v.position, `corner ${c}`);
    assert.deepEqual(Array.from(slots.normals.subarray(3 * c, 3 * c + 3)), v.normal, `corner ${c}`);
  }
});

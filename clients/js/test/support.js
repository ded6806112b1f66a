// Test support: hand-made binary frames whose mesh payload is a stand-in for Draco (JSON of the
// decoded mesh), read back by FakeMeshDecoder, so that frame and mesh logic is tested without
// the WebAssembly decoder. (The real payloads are covered by cpp_conformance.test.js.)

import { FRAME_HEADER_BYTES } from '../src/frame.js';
import { encodeIdSequence, encodeSortedIds } from '../src/varint.js';

export const SESSION = '00112233445566778899aabbccddeeff';

/**
 * A mesh payload: `vertices` [[id, x, y, z, nx, ny, nz], ...] and `triangles` [[a, b, c], ...]
 * by vertex id. Each vertex becomes one Draco-like point.
 */
export function payload(vertices, triangles) {
  const index = new Map(vertices.map((v, p) => [v[0], p]));
  const mesh = {
    pointCount: vertices.length,
    globalIds: vertices.map((v) => v[0]),
    positions: vertices.flatMap((v) => v.slice(1, 4)),
    normals: vertices.flatMap((v) => v.slice(4, 7)),
    faces: triangles.flatMap((t) => t.map((id) => index.get(id) ?? 999)),
  };
  return new TextEncoder().encode(JSON.stringify(mesh));
}

export class FakeMeshDecoder {
  decode(bytes) {
    const m = JSON.parse(new TextDecoder().decode(bytes));
    return {
      pointCount: m.pointCount,
      globalIds: Uint32Array.from(m.globalIds),
      positions: Float32Array.from(m.positions),
      normals: Float32Array.from(m.normals),
      faces: Uint32Array.from(m.faces),
    };
  }
}

/**
 * Assembles a frame. `mesh` = {vertices, triangles} as for payload(); `triangleIds` gives explicit
 * ids (keyframes), otherwise triangle i gets baseTriangleId + i. `override` replaces header fields.
 */
export function buildFrame({
  kind = 'delta',
  flags = 0,
  session = SESSION,
  sequence = 0,
  timestampUs = 1_700_000_000_000_000,
  baseTriangleId = 0,
  functionVersion = 1,
  removed = [],
  triangleIds = null,
  mesh = null,
  override = {},
} = {}) {
  const removedBytes = encodeSortedIds(removed);
  const idBytes = triangleIds ? encodeIdSequence(triangleIds, baseTriangleId) : new Uint8Array(0);
  const meshBytes = mesh ? payload(mesh.vertices, mesh.triangles) : new Uint8Array(0);
  const triangleCount = mesh ? mesh.triangles.length : 0;
  const h = {
    version: 1,
    kind: kind === 'keyframe' ? 1 : 2,
    flags,
    sequence,
    timestampUs,
    baseTriangleId,
    functionVersion,
    removedCount: removed.length,
    triangleCount,
    pointCount: mesh ? mesh.vertices.length : 0,
    removedBytes: removedBytes.length,
    triangleIdsBytes: idBytes.length,
    meshBytes: meshBytes.length,
    ...override,
  };
  const bytes = new Uint8Array(FRAME_HEADER_BYTES + removedBytes.length + idBytes.length + meshBytes.length);
  const view = new DataView(bytes.buffer);
  bytes.set([0x49, 0x53, 0x4f, 0x4d, h.version, h.kind]);
  view.setUint16(6, h.flags, true);
  for (let i = 0; i < 16; ++i) bytes[8 + i] = parseInt(session.slice(2 * i, 2 * i + 2), 16);
  view.setBigUint64(24, BigInt(h.sequence), true);
  view.setBigUint64(32, BigInt(h.timestampUs), true);
  view.setBigUint64(40, BigInt(h.baseTriangleId), true);
  const u32 = [h.functionVersion, h.removedCount, h.triangleCount, h.pointCount, h.removedBytes, h.triangleIdsBytes, h.meshBytes];
  u32.forEach((value, i) => view.setUint32(48 + 4 * i, value, true));
  let offset = FRAME_HEADER_BYTES;
  for (const section of [removedBytes, idBytes, meshBytes]) {
    bytes.set(section, offset);
    offset += section.length;
  }
  return bytes;
}

/** A vertex [id, x, y, z, nx, ny, nz] with values derived from its id. */
export function vertex(id, shift = 0) {
  return [id, id + shift, 2 * id, -id, 0, 0, 1];
}

/** xorshift32: a deterministic sequence in [0, 1) for the randomized tests. */
export function random(seed) {
  let x = seed;
  return () => {
    x ^= x << 13;
    x ^= x >>> 17;
    x ^= x << 5;
    return (x >>> 0) / 2 ** 32;
  };
}

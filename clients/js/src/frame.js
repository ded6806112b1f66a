// Binary frames: the mesh data of the isomesh protocol (PROTOCOL.md, "Binary frames"), versions 1
// and 2. A version-2 keyframe has a 20-byte grid block after the header and octahedral normals in
// its payload; a version-2 delta (delta_v2.js) is decoded later, against the held mesh.
//
// A frame is a fixed 76-byte little-endian header, then three sections whose lengths the header
// gives: removed triangle ids (sorted, delta-coded varints), explicit triangle ids (optional,
// zigzag delta-coded varints; absent: triangle i of the payload has id base + i), and the Draco
// mesh payload of the added triangles.
//
//   offset size field
//        0    4 magic "ISOM"
//        4    1 protocol version (1)
//        5    1 kind: 1 keyframe, 2 delta
//        6    2 flags (bit 0 converged, bit 1 catch_up)
//        8   16 session id
//       24    8 sequence number
//       32    8 server timestamp, microseconds since the Unix epoch
//       40    8 base triangle id
//       48    4 function version
//       52    4 removed triangle count
//       56    4 added triangle count
//       60    4 mesh payload point count
//       64    4 removed ids length in bytes
//       68    4 explicit triangle ids length in bytes
//       72    4 mesh payload length in bytes

import { IsomeshError } from './errors.js';
import { DELTA_V2_HEADER_BYTES, readDeltaV2Header } from './delta_v2.js';
import { GridMath } from './delta_v2_geometry.js';
import { PROTOCOL_VERSIONS } from './messages.js';
import { MAX_TRIANGLE_ID, decodeIdSequence, decodeSortedIds } from './varint.js';

export const FRAME_HEADER_BYTES = 76;
/** Version-2 keyframes: the grid block after the header. */
export const GRID_BLOCK_BYTES = 20;
/** Most triangles, added or removed, in one frame. */
export const MAX_FRAME_TRIANGLES = 2 ** 22;
export const FRAME_FLAG_CONVERGED = 1;
export const FRAME_FLAG_CATCH_UP = 2;

const MAGIC = [0x49, 0x53, 0x4f, 0x4d]; // "ISOM"
const KINDS = { 1: 'keyframe', 2: 'delta' };

/**
 * Reads and validates the header of a frame (a Uint8Array). Throws IsomeshError with code
 * 'bad_frame' (or 'unsupported_version') when it is malformed. Section lengths are checked
 * against the frame by decodeFrame.
 */
export function readFrameHeader(bytes) {
  if (bytes.length < DELTA_V2_HEADER_BYTES) throw frameError('frame shorter than its header');
  if (!MAGIC.every((b, i) => bytes[i] === b)) throw frameError('frame does not start with ISOM');
  const version = bytes[4];
  if (!PROTOCOL_VERSIONS.includes(version)) {
    throw new IsomeshError('unsupported_version', `frame of protocol version ${version}`);
  }
  const kind = KINDS[bytes[5]];
  if (!kind) throw frameError(`unknown frame kind ${bytes[5]}`);
  const common = readCommonHeader(bytes, version, kind);
  if (version === 2 && kind === 'delta') return readDeltaV2Header(bytes, common);
  if (bytes.length < FRAME_HEADER_BYTES) throw frameError('frame shorter than its 76-byte header');
  const view = new DataView(bytes.buffer, bytes.byteOffset, FRAME_HEADER_BYTES);
  const u32 = (offset) => view.getUint32(offset, true);
  const h = {
    ...common,
    baseTriangleId: safeU64(view, 40, 'base triangle id'),
    functionVersion: u32(48),
    removedCount: u32(52),
    triangleCount: u32(56),
    pointCount: u32(60),
    removedBytes: u32(64),
    triangleIdsBytes: u32(68),
    meshBytes: u32(72),
  };
  checkHeader(h);
  if (version === 2) h.grid = readGridBlock(bytes);
  return h;
}

/** Magic to timestamp: the fields every frame of both versions shares. */
function readCommonHeader(bytes, version, kind) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, 40);
  const flags = view.getUint16(6, true);
  return {
    version,
    kind,
    flags,
    converged: (flags & FRAME_FLAG_CONVERGED) !== 0,
    catchUp: (flags & FRAME_FLAG_CATCH_UP) !== 0,
    session: toHex(bytes.subarray(8, 24)),
    sequence: safeU64(view, 24, 'sequence number'),
    timestampUs: safeU64(view, 32, 'timestamp'),
  };
}

/** The grid block of a version-2 keyframe (PROTOCOL.md 4.5), after the 76-byte header. */
function readGridBlock(bytes) {
  if (bytes.length < FRAME_HEADER_BYTES + GRID_BLOCK_BYTES) {
    throw frameError('version-2 keyframe shorter than its header and grid block');
  }
  const view = new DataView(bytes.buffer, bytes.byteOffset + FRAME_HEADER_BYTES, GRID_BLOCK_BYTES);
  const grid = {
    origin: [0, 4, 8].map((o) => view.getFloat32(o, true)),
    range: view.getFloat32(12, true),
    positionBits: view.getUint8(16),
    normalBits: view.getUint8(17),
  };
  const finite = [...grid.origin, grid.range].every(Number.isFinite);
  if (!finite || !(grid.range > 0) || grid.positionBits < 1 || grid.positionBits > 30 ||
      grid.normalBits < 2 || grid.normalBits > 30) {
    throw frameError('invalid quantization grid');
  }
  return grid;
}

function checkHeader(h) {
  if (h.functionVersion === 0) throw frameError('function version 0');
  if (h.removedCount > MAX_FRAME_TRIANGLES || h.triangleCount > MAX_FRAME_TRIANGLES) {
    throw frameError('more than 2^22 triangles in one frame');
  }
  if (h.kind === 'keyframe' && h.removedCount > 0) throw frameError('a keyframe removes nothing');
  if ((h.triangleCount === 0) !== (h.meshBytes === 0)) {
    throw frameError('mesh payload length disagrees with the triangle count');
  }
  if ((h.triangleCount === 0) !== (h.pointCount === 0) || h.pointCount > 3 * h.triangleCount) {
    throw frameError('point count disagrees with the triangle count');
  }
  if (h.triangleIdsBytes === 0 && h.triangleCount > 0 && h.triangleCount - 1 > MAX_TRIANGLE_ID - h.baseTriangleId) {
    throw frameError('triangle ids exceed 2^53 - 1');
  }
}

/**
 * Decodes and validates a whole frame.
 * @param {Uint8Array} bytes the binary WebSocket message
 * @param {{decode(bytes: Uint8Array): object}} meshDecoder a DracoMeshDecoder
 * @returns {{header: object, removed: number[], triangleIds: number[], mesh: object|null}}
 *   `removed` ascending; `triangleIds[i]` is the id of payload triangle i; `mesh` is what
 *   DracoMeshDecoder.decode returns (null when the frame adds nothing). A version-2 delta comes
 *   back undecoded: {header, body} (SessionMesh.apply decodes it against the mesh it holds).
 */
export function decodeFrame(bytes, meshDecoder) {
  const header = readFrameHeader(bytes);
  if (header.version === 2 && header.kind === 'delta') {
    // Decoded against the held mesh, and only when it is the next frame (SessionMesh.apply).
    return { header, body: bytes.subarray(DELTA_V2_HEADER_BYTES), removed: null, triangleIds: null, mesh: null };
  }
  const start = FRAME_HEADER_BYTES + (header.version === 2 ? GRID_BLOCK_BYTES : 0);
  const expected = start + header.removedBytes + header.triangleIdsBytes + header.meshBytes;
  if (expected !== bytes.length) {
    throw frameError(`frame of ${bytes.length} bytes, header says ${expected}`);
  }
  let offset = start;
  const section = (length) => bytes.subarray(offset, (offset += length));
  const removedSection = section(header.removedBytes);
  const idsSection = section(header.triangleIdsBytes);
  const meshSection = section(header.meshBytes);

  const removed = decodeSortedIds(removedSection, header.removedCount);
  const triangleIds = decodeTriangleIds(header, idsSection);
  if (header.triangleCount === 0) return { header, removed, triangleIds, mesh: null };

  const mesh = meshDecoder.decode(meshSection, header.grid ? new GridMath(header.grid) : null);
  if (mesh.faces.length !== 3 * header.triangleCount || mesh.pointCount !== header.pointCount) {
    throw frameError('mesh payload counts disagree with the header');
  }
  checkWelding(mesh);
  return { header, removed, triangleIds, mesh };
}

function decodeTriangleIds(header, bytes) {
  const count = header.triangleCount;
  if (header.triangleIdsBytes === 0) {
    return Array.from({ length: count }, (_, i) => header.baseTriangleId + i);
  }
  const ids = decodeIdSequence(bytes, count, header.baseTriangleId);
  if (new Set(ids).size !== ids.length) throw frameError('triangle ids repeat');
  return ids;
}

/**
 * Points that share a global id are one vertex: they must carry identical values. A triangle must
 * use three distinct vertices.
 */
function checkWelding(mesh) {
  const { globalIds, positions, normals, faces } = mesh;
  const firstPoint = new Map();
  for (let p = 0; p < globalIds.length; ++p) {
    const first = firstPoint.get(globalIds[p]);
    if (first === undefined) {
      firstPoint.set(globalIds[p], p);
    } else if (!sameVertex(positions, normals, first, p)) {
      throw frameError(`global id ${globalIds[p]} has two different values`);
    }
  }
  for (let f = 0; f < faces.length; f += 3) {
    const [a, b, c] = [globalIds[faces[f]], globalIds[faces[f + 1]], globalIds[faces[f + 2]]];
    if (a === undefined || b === undefined || c === undefined) throw frameError('face uses a missing point');
    if (a === b || b === c || a === c) throw frameError('a triangle repeats a vertex');
  }
}

function sameVertex(positions, normals, p, q) {
  for (let k = 0; k < 3; ++k) {
    if (positions[3 * p + k] !== positions[3 * q + k] || normals[3 * p + k] !== normals[3 * q + k]) {
      return false;
    }
  }
  return true;
}

function safeU64(view, offset, what) {
  const value = view.getBigUint64(offset, true);
  if (value > BigInt(Number.MAX_SAFE_INTEGER)) throw frameError(`${what} exceeds 2^53 - 1`);
  return Number(value);
}

export function toHex(bytes) {
  let hex = '';
  for (const b of bytes) hex += b.toString(16).padStart(2, '0');
  return hex;
}

function frameError(message) {
  return new IsomeshError('bad_frame', message);
}

// A JavaScript reader of isomesh binary frames, written from protocol/PROTOCOL.md alone: the
// 76-byte header, the varint id lists and the Draco mesh payload (decoded with Google's draco3d).
// Triangle ids are Numbers (the protocol keeps them below 2^53).

export const HEADER_BYTES = 76;
export const MAX_TRIANGLE_ID = 2 ** 53 - 1;
export const KIND = { 1: 'keyframe', 2: 'delta' };
export const FLAGS = { converged: 1, catch_up: 2 };

function fail(message) {
  throw new Error(`bad frame: ${message}`);
}

/** Parses the fixed header of `bytes` (a Uint8Array). */
export function readHeader(bytes) {
  if (bytes.length < HEADER_BYTES) fail('shorter than the header');
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (String.fromCharCode(...bytes.subarray(0, 4)) !== 'ISOM') fail('no ISOM magic');
  if (bytes[4] !== 1) fail(`protocol version ${bytes[4]}`);
  if (!KIND[bytes[5]]) fail(`kind ${bytes[5]}`);
  const u32 = (offset) => view.getUint32(offset, true);
  const u64 = (offset) => Number(view.getBigUint64(offset, true));
  return {
    kind: KIND[bytes[5]],
    flags: view.getUint16(6, true),
    session: Buffer.from(bytes.subarray(8, 24)).toString('hex'),
    sequence: u64(24),
    timestamp_us: u64(32),
    base_triangle_id: u64(40),
    function_version: u32(48),
    removed_count: u32(52),
    triangle_count: u32(56),
    point_count: u32(60),
    removed_bytes: u32(64),
    triangle_ids_bytes: u32(68),
    mesh_bytes: u32(72),
  };
}

/** Reads `count` unsigned LEB128 varints filling `bytes` exactly, as BigInts. */
export function readVarints(bytes, count) {
  const values = [];
  let offset = 0;
  for (let i = 0; i < count; i++) {
    let value = 0n;
    let shift = 0n;
    for (;;) {
      if (offset >= bytes.length) fail('truncated varint');
      const byte = bytes[offset++];
      value |= BigInt(byte & 0x7f) << shift;
      shift += 7n;
      if ((byte & 0x80) === 0) break;
      if (shift >= 70n) fail('varint too long');
    }
    values.push(value);
  }
  if (offset !== bytes.length) fail('bytes left after the varints');
  return values;
}

function safeId(value) {
  if (value < 0n || value > BigInt(MAX_TRIANGLE_ID)) fail('triangle id out of range');
  return Number(value);
}

/** Removed ids: the first id, then differences to the previous one. */
export function decodeSortedIds(bytes, count) {
  let id = 0n;
  return readVarints(bytes, count).map((step) => safeId((id += step)));
}

/** Explicit ids: zigzag differences, the first from `base`. */
export function decodeIdSequence(bytes, count, base) {
  let id = BigInt(base);
  return readVarints(bytes, count).map((z) => {
    id += z & 1n ? -((z + 1n) >> 1n) : z >> 1n;
    return safeId(id);
  });
}

function heapCopy(draco, ArrayType, heap, byteLength, fill) {
  const pointer = draco._malloc(byteLength);
  try {
    fill(pointer);
    return new ArrayType(heap().buffer, pointer, byteLength / ArrayType.BYTES_PER_ELEMENT).slice();
  } finally {
    draco._free(pointer);
  }
}

/**
 * Decodes a Draco mesh payload: per Draco point its global id, position and normal, and `faces`
 * (3 point indices per triangle, in decoded order).
 */
export function decodeMeshPayload(draco, payload) {
  const decoder = new draco.Decoder();
  const buffer = new draco.DecoderBuffer();
  const mesh = new draco.Mesh();
  try {
    buffer.Init(new Int8Array(payload.buffer, payload.byteOffset, payload.byteLength), payload.byteLength);
    if (decoder.GetEncodedGeometryType(buffer) !== draco.TRIANGULAR_MESH) fail('not a Draco mesh');
    const status = decoder.DecodeBufferToMesh(buffer, mesh);
    if (!status.ok()) fail(`Draco: ${status.error_msg()}`);
    const pointCount = mesh.num_points();
    const faceCount = mesh.num_faces();
    const globalIdAttribute = decoder.GetAttributeIdByMetadataEntry(mesh, 'name', 'global_id');
    if (globalIdAttribute < 0) fail('no attribute with metadata name=global_id');
    const attribute = (id) => decoder.GetAttribute(mesh, id);
    const floats = (id) =>
      heapCopy(draco, Float32Array, () => draco.HEAPF32, pointCount * 12, (pointer) =>
        decoder.GetAttributeDataArrayForAllPoints(mesh, attribute(id), draco.DT_FLOAT32, pointCount * 12, pointer));
    const positions = floats(decoder.GetAttributeId(mesh, draco.POSITION));
    const normals = floats(decoder.GetAttributeId(mesh, draco.NORMAL));
    const ids = heapCopy(draco, Uint32Array, () => draco.HEAPU32, pointCount * 4, (pointer) =>
      decoder.GetAttributeDataArrayForAllPoints(mesh, attribute(globalIdAttribute), draco.DT_UINT32, pointCount * 4, pointer));
    const faces = heapCopy(draco, Uint32Array, () => draco.HEAPU32, faceCount * 12, (pointer) =>
      decoder.GetTrianglesUInt32Array(mesh, faceCount * 12, pointer));
    return {
      uniqueIdOfGlobalId: attribute(globalIdAttribute).unique_id(),
      pointCount,
      ids,
      positions,
      normals,
      faces,
    };
  } finally {
    draco.destroy(mesh);
    draco.destroy(buffer);
    draco.destroy(decoder);
  }
}

function vertexAt(points, p) {
  return {
    position: Array.from(points.positions.subarray(3 * p, 3 * p + 3)),
    normal: Array.from(points.normals.subarray(3 * p, 3 * p + 3)),
  };
}

/**
 * Decodes a whole frame: { header, removed, vertices: Map(globalId -> {position, normal}),
 * triangles: [{ id, vertices: [globalId x3] }] in decoded order }.
 */
export function decodeFrame(draco, bytes) {
  const header = readHeader(bytes);
  const total = HEADER_BYTES + header.removed_bytes + header.triangle_ids_bytes + header.mesh_bytes;
  if (total !== bytes.length) fail(`length ${bytes.length}, header says ${total}`);
  if (header.kind === 'keyframe' && header.removed_count > 0) fail('keyframe removes triangles');
  let offset = HEADER_BYTES;
  const section = (length) => bytes.subarray(offset, (offset += length));
  const removed = decodeSortedIds(section(header.removed_bytes), header.removed_count);
  const idBytes = section(header.triangle_ids_bytes);
  const ids =
    header.triangle_ids_bytes > 0
      ? decodeIdSequence(idBytes, header.triangle_count, header.base_triangle_id)
      : Array.from({ length: header.triangle_count }, (_, i) => header.base_triangle_id + i);
  const vertices = new Map();
  const triangles = [];
  if (header.triangle_count > 0) {
    const payload = decodeMeshPayload(draco, section(header.mesh_bytes));
    if (payload.faces.length !== 3 * header.triangle_count) fail('triangle count differs');
    if (payload.pointCount !== header.point_count) fail('point count differs');
    for (let p = 0; p < payload.pointCount; p++) vertices.set(payload.ids[p], vertexAt(payload, p));
    for (let t = 0; t < header.triangle_count; t++) {
      const corners = payload.faces.subarray(3 * t, 3 * t + 3);
      triangles.push({ id: ids[t], vertices: Array.from(corners, (p) => payload.ids[p]) });
    }
  }
  return { header, removed, vertices, triangles };
}

/** A client's mesh of one session, following PROTOCOL.md "Applying frames". */
export class Replica {
  constructor() {
    this.synchronized = false;
    this.sequence = 0;
    this.triangles = new Map(); // triangle id -> [globalId x3]
    this.vertices = new Map(); // global id -> {position, normal}
  }

  /** Returns 'applied', 'stale', 'awaiting_keyframe' or 'gap' (then send resync). */
  apply(frame) {
    const { header } = frame;
    if (header.kind === 'keyframe') {
      this.triangles.clear();
      this.vertices.clear();
    } else if (!this.synchronized) {
      return 'awaiting_keyframe';
    } else if (header.sequence <= this.sequence) {
      return 'stale';
    } else if (header.sequence !== this.sequence + 1) {
      this.synchronized = false;
      return 'gap';
    }
    for (const id of frame.removed) this.triangles.delete(id);
    for (const [id, vertex] of frame.vertices) this.vertices.set(id, vertex);
    for (const t of frame.triangles) this.triangles.set(t.id, t.vertices);
    this.synchronized = true;
    this.sequence = header.sequence;
    return 'applied';
  }
}

/** Corners rotated to start at the smallest id (decoding may rotate, never mirror). */
export function canonical([a, b, c]) {
  if (a <= b && a <= c) return [a, b, c];
  if (b <= a && b <= c) return [b, c, a];
  return [c, a, b];
}

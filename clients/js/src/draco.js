// Decoding the mesh payload of binary frames (PROTOCOL.md, "The mesh payload") with Google's
// Draco decoder compiled to WebAssembly (npm `draco3d`).
//
// A payload is a Draco triangle mesh with three per-point attributes: float32 positions (unique id
// 0), float32 normals (unique id 1) and a uint32 GENERIC attribute whose metadata entry
// name = "global_id" holds each point's session-wide vertex id. Draco may split a vertex into
// several points; the global id welds them back. Triangles keep Draco's decoded order: the
// frame numbers them by it.

import { IsomeshError } from './errors.js';

const POSITION_UNIQUE_ID = 0;
const NORMAL_UNIQUE_ID = 1;

/**
 * Wraps an initialized draco3d decoder module (what `createDecoderModule()` resolves to).
 * One instance owns one Draco `Decoder`; call dispose() to free it.
 */
export class DracoMeshDecoder {
  constructor(draco) {
    if (!draco || typeof draco.Decoder !== 'function') {
      throw new TypeError('DracoMeshDecoder needs an initialized draco3d decoder module');
    }
    this.draco = draco;
    this.decoder = new draco.Decoder();
  }

  /**
   * Decodes one payload (a Uint8Array).
   * @returns {{pointCount: number, globalIds: Uint32Array, positions: Float32Array,
   *            normals: Float32Array, faces: Uint32Array}} per-point attributes (3 floats per
   *   point for positions and normals) and 3 point indices per triangle, in decoded order.
   * Throws IsomeshError('bad_frame') on anything that is not such a mesh.
   */
  decode(bytes, octahedral = null) {
    const { draco, decoder } = this;
    if (decoder.GetEncodedGeometryType(bytes) !== draco.TRIANGULAR_MESH) {
      throw frameError('mesh payload is not a Draco triangle mesh');
    }
    const mesh = new draco.Mesh();
    try {
      const status = decoder.DecodeArrayToMesh(bytes, bytes.byteLength, mesh);
      if (!status.ok() || mesh.ptr === 0) throw frameError(`Draco: ${status.error_msg()}`);
      const pointCount = mesh.num_points();
      const position = this.#byUniqueId(mesh, POSITION_UNIQUE_ID, draco.POSITION, 'position');
      const positions = this.#floatAttribute(mesh, position);
      const normals = octahedral
        ? this.#octahedralNormals(mesh, octahedral)
        : this.#floatAttribute(mesh, this.#byUniqueId(mesh, NORMAL_UNIQUE_ID, draco.NORMAL, 'normal'));
      const globalIds = this.#globalIds(mesh);
      const faces = this.#faces(mesh);
      return { pointCount, globalIds, positions, normals, faces };
    } finally {
      draco.destroy(mesh);
    }
  }

  dispose() {
    if (this.decoder) this.draco.destroy(this.decoder);
    this.decoder = null;
  }

  #byUniqueId(mesh, uniqueId, type, what) {
    const attribute = this.decoder.GetAttributeByUniqueId(mesh, uniqueId);
    const fits =
      attribute &&
      attribute.ptr !== 0 &&
      attribute.attribute_type() === type &&
      attribute.data_type() === this.draco.DT_FLOAT32 &&
      attribute.num_components() === 3;
    if (!fits) {
      throw frameError(`mesh payload lacks a float32 ${what} attribute (unique id ${uniqueId})`);
    }
    return attribute;
  }

  #floatAttribute(mesh, attribute) {
    const { draco } = this;
    const count = mesh.num_points() * 3;
    return this.#copyOut(count, Float32Array, (bytes, ptr) =>
      this.decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, draco.DT_FLOAT32, bytes, ptr),
    );
  }

  /**
   * Version-2 payloads (PROTOCOL.md 4.5): the normal attribute is GENERIC int16 x 2, metadata
   * name = "octahedral_normal", holding octahedral codes that `octahedral` (a GridMath) decodes.
   */
  #octahedralNormals(mesh, octahedral) {
    const { draco, decoder } = this;
    const id = decoder.GetAttributeIdByMetadataEntry(mesh, 'name', 'octahedral_normal');
    const attribute = id >= 0 ? decoder.GetAttribute(mesh, id) : null;
    if (!attribute || attribute.num_components() !== 2 || attribute.data_type() !== draco.DT_INT16) {
      throw frameError('version-2 payload lacks an int16 x 2 octahedral_normal attribute');
    }
    const codes = this.#copyOut(mesh.num_points() * 2, Int16Array, (bytes, ptr) =>
      decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, draco.DT_INT16, bytes, ptr),
    );
    const normals = new Float32Array(mesh.num_points() * 3);
    for (let p = 0; p < mesh.num_points(); ++p) {
      if (!octahedral.validNormalCode(codes[2 * p], codes[2 * p + 1])) throw frameError('octahedral normal out of range');
      octahedral.decodeNormalInto(codes[2 * p], codes[2 * p + 1], normals, 3 * p);
    }
    return normals;
  }

  #globalIds(mesh) {
    const { draco, decoder } = this;
    const id = decoder.GetAttributeIdByMetadataEntry(mesh, 'name', 'global_id');
    const attribute = id >= 0 ? decoder.GetAttribute(mesh, id) : null;
    if (!attribute || attribute.num_components() !== 1 || attribute.data_type() !== draco.DT_UINT32) {
      throw frameError('mesh payload lacks a uint32 global_id attribute');
    }
    return this.#copyOut(mesh.num_points(), Uint32Array, (bytes, ptr) =>
      decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, draco.DT_UINT32, bytes, ptr),
    );
  }

  #faces(mesh) {
    return this.#copyOut(mesh.num_faces() * 3, Uint32Array, (bytes, ptr) =>
      this.decoder.GetTrianglesUInt32Array(mesh, bytes, ptr),
    );
  }

  /** Calls `fill(byteLength, ptr)` on a scratch WebAssembly buffer and copies the result out. */
  #copyOut(count, ArrayType, fill) {
    const { draco } = this;
    const byteLength = count * ArrayType.BYTES_PER_ELEMENT;
    const ptr = draco._malloc(Math.max(byteLength, 4));
    try {
      if (!fill(byteLength, ptr)) throw frameError('mesh payload attribute data is truncated');
      // Read the heap view only now: decoding may have grown the WebAssembly memory.
      const heap = { Float32Array: draco.HEAPF32, Int16Array: draco.HEAP16 }[ArrayType.name] ?? draco.HEAPU32;
      return new ArrayType(heap.buffer, ptr, count).slice();
    } finally {
      draco._free(ptr);
    }
  }
}

function frameError(message) {
  return new IsomeshError('bad_frame', message);
}

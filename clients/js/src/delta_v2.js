// Version-2 deltas (PROTOCOL.md 4.5.2): a 56-byte header and one range-coded body, decoded
// against the mesh the client holds. A port of the decoder of protocol/delta_v2_decoder.cpp: splits of
// held edges (new vertices predicted from the split edge), explicit removals, loose vertices,
// explicit triangles, moved vertices. The result has the shape of decodeFrame's, so a
// SessionMesh applies it as a version-1 delta.
//
// The body's changes are made in place on the held mesh (DeltaEdit, which can undo them), on
// vertex and triangle slots: a delta of n splits costs O(n) typed-array work, whatever the size of
// the mesh it refines.

import { DeltaEdit, MAX_VERTEX_ID, frameError } from './delta_v2_edit.js';
import { GridMath } from './delta_v2_geometry.js';
import { NONE } from './id_index.js';
import { RangeDecoder, bitModel, intModel } from './range_decoder.js';
import { MAX_TRIANGLE_ID } from './varint.js';

export const DELTA_V2_HEADER_BYTES = 56;
const MAX_CHANGES = 2 ** 22;

function models() {
  return {
    count: intModel(),
    splitGap: intModel(),
    edgeMiss: bitModel(),
    edgeSecond: bitModel(),
    position: intModel(),
    normal: intModel(),
    removedGap: intModel(),
    vertexStep: intModel(),
    movedGap: intModel(),
    movedOffset: intModel(),
    movedPosition: intModel(),
    movedNormal: intModel(),
  };
}

/** Reads a version-2 delta's header (the first 24 bytes are checked by the caller). */
export function readDeltaV2Header(bytes, common) {
  if (bytes.length < DELTA_V2_HEADER_BYTES) throw frameError('version-2 delta shorter than its 56-byte header');
  const view = new DataView(bytes.buffer, bytes.byteOffset, DELTA_V2_HEADER_BYTES);
  const base = view.getBigUint64(40, true);
  if (base > BigInt(MAX_TRIANGLE_ID)) throw frameError('triangle ids exceed 2^53 - 1');
  const header = {
    ...common,
    baseTriangleId: Number(base),
    functionVersion: view.getUint32(48, true),
    baseVertexId: view.getUint32(52, true),
  };
  if (header.functionVersion === 0) throw frameError('function version 0');
  return header;
}

/**
 * Decodes the body of a version-2 delta against `held` (a HeldMesh: the session's mesh after the
 * frame before) on `grid` (the last keyframe's). Returns {header, removed, triangleIds, mesh}
 * like decodeFrame, mesh holding every vertex the added triangles use and every moved vertex still
 * in use. Throws IsomeshError('bad_frame') on a malformed body or one that does not fit `held`.
 * `held` is left as it was (applyDeltaV2 also applies the delta to it).
 */
export function decodeDeltaV2(header, body, held, grid) {
  const edit = decodeInto(header, body, held, grid);
  const result = edit.result(header);
  edit.rollback();
  return result;
}

/**
 * decodeDeltaV2, and `held` becomes the mesh after the delta (as held.apply(result) would make
 * it). On a bad_frame error `held` is left as it was.
 */
export function applyDeltaV2(header, body, held, grid) {
  const edit = decodeInto(header, body, held, grid);
  const result = edit.result(header);
  edit.commit();
  return result;
}

/** The body's changes made on `held`; undone before an error propagates. */
function decodeInto(header, body, held, grid) {
  const edit = new DeltaEdit(held, header.baseTriangleId, header.baseVertexId);
  try {
    const reader = new BodyReader(body, edit, new GridMath(grid));
    reader.splits();
    reader.removals();
    reader.looseVertices();
    reader.triangles();
    reader.moved();
  } catch (error) {
    edit.rollback();
    throw error;
  }
  return edit;
}

/** The body's five parts, read in order (PROTOCOL.md 4.5.2); each makes its changes on `edit`. */
class BodyReader {
  constructor(body, edit, math) {
    this.coder = new RangeDecoder(body);
    this.models = models();
    this.edit = edit;
    this.held = edit.held;
    this.math = math;
    // Scratch: grid points of a split edge's ends, a new point and a normal code. Doubles, so that
    // a residual that pushes a coordinate far off the grid is caught, not wrapped.
    this.p = new Float64Array(3);
    this.q = new Float64Array(3);
    this.point = new Float64Array(3);
    this.normal = new Float64Array(2);
  }

  count() {
    const n = this.coder.uint(this.models.count);
    if (n > MAX_CHANGES) throw frameError('more than 2^22 changes in one frame');
    return n;
  }

  splits() {
    const rounds = this.count();
    let total = 0;
    for (let round = 0; round < rounds; ++round) {
      const n = this.count();
      if ((total += n) > MAX_CHANGES) throw frameError('more than 2^22 splits');
      let previous = 0;
      for (let i = 0; i < n; ++i) {
        const t = previous + this.coder.uint(this.models.splitGap) + (i === 0 ? 0 : 1);
        if (t > MAX_TRIANGLE_ID) throw frameError('bad split triangle id');
        previous = t;
        this.split(t);
      }
    }
  }

  /** One split of held triangle `t`: its edge, the new vertex's residuals, the bisection. */
  split(t) {
    const { coder, models: m, held, math, edit } = this;
    const slot = edit.triangleSlot(t);
    if (slot === NONE) throw frameError(`split of triangle ${t}, not held`);
    let miss = coder.bit(m.edgeMiss);
    if (miss !== 0 && coder.bit(m.edgeSecond)) miss = 2;
    const e = (predictedEdge(held, slot) + miss) % 3;
    const a = held.corners[3 * slot + e];
    const b = held.corners[3 * slot + ((e + 1) % 3)];
    const { p, q, point, normal } = this;
    math.recoverInto(held.positions, 3 * a, p, 0);
    math.recoverInto(held.positions, 3 * b, q, 0);
    math.predictSplitInto(p, 0, q, 0, held.normals, 3 * a, held.normals, 3 * b, point);
    for (let axis = 0; axis < 3; ++axis) point[axis] += coder.sint(m.position);
    const n = held.normals;
    math.encodeNormalInto(n[3 * a] + n[3 * b], n[3 * a + 1] + n[3 * b + 1], n[3 * a + 2] + n[3 * b + 2], normal, 0);
    for (let k = 0; k < 2; ++k) normal[k] += coder.sint(m.normal);
    if (!math.validPoint(point) || !math.validNormal(normal)) throw frameError('split vertex off the grid');
    const v = edit.newVertex();
    edit.checkFreshTriangleIds(4);
    this.#setVertex(v);
    edit.split(slot, e, v);
  }

  removals() {
    const n = this.count();
    let previous = 0;
    for (let i = 0; i < n; ++i) {
      const id = previous + this.coder.uint(this.models.removedGap) + (i === 0 ? 0 : 1);
      previous = id;
      const slot = this.edit.triangleSlot(id);
      if (slot === NONE) throw frameError(`removes triangle ${id}, not held`);
      this.edit.removeTriangle(slot);
    }
  }

  looseVertices() {
    const { coder, math, point, normal } = this;
    const n = this.count();
    const { positionBits, normalBits } = math.grid;
    for (let i = 0; i < n; ++i) {
      for (let axis = 0; axis < 3; ++axis) point[axis] = coder.direct(positionBits);
      for (let k = 0; k < 2; ++k) normal[k] = coder.direct(normalBits) - math.maxOctahedral;
      if (!math.validPoint(point) || !math.validNormal(normal)) throw frameError('loose vertex off the grid');
      this.#setVertex(this.edit.newVertex());
    }
  }

  triangles() {
    const { coder, models: m, edit } = this;
    const n = this.count();
    const c = [0, 0, 0];
    let last = 0;
    for (let i = 0; i < n; ++i) {
      for (let k = 0; k < 3; ++k) {
        const id = last + coder.sint(m.vertexStep);
        if (id < 0 || id > MAX_VERTEX_ID) throw frameError('bad vertex id');
        c[k] = last = id;
        if (edit.vertexSlot(id) === NONE) throw frameError(`a triangle uses unknown vertex ${id}`);
      }
      if (c[0] === c[1] || c[1] === c[2] || c[0] === c[2]) throw frameError('a triangle repeats a vertex');
      edit.checkFreshTriangleIds(1);
      edit.addTriangle(edit.vertexSlot(c[0]), edit.vertexSlot(c[1]), edit.vertexSlot(c[2]));
    }
  }

  moved() {
    const { coder, models: m, held, math, edit, point, normal } = this;
    const n = this.count();
    const maxOffset = 2 * math.maxCoordinate + 2;
    let previous = 0;
    let offset = 0;
    for (let i = 0; i < n; ++i) {
      const id = previous + coder.uint(m.movedGap) + (i === 0 ? 0 : 1);
      if (id > MAX_VERTEX_ID) throw frameError('bad moved vertex id');
      previous = id;
      const v = edit.vertexSlot(id);
      if (v === NONE) throw frameError(`moves vertex ${id}, not held`);
      // Along the held normal, by the previous moved vertex's offset plus a residual (4.5.2, 5).
      offset += coder.sint(m.movedOffset);
      if (Math.abs(offset) > maxOffset) throw frameError('moved vertex offset out of range');
      math.recoverInto(held.positions, 3 * v, point, 0);
      math.predictMoveInto(point, held.normals, 3 * v, offset);
      math.encodeNormalInto(held.normals[3 * v], held.normals[3 * v + 1], held.normals[3 * v + 2], normal, 0);
      for (let axis = 0; axis < 3; ++axis) point[axis] += coder.sint(m.movedPosition);
      for (let k = 0; k < 2; ++k) normal[k] += coder.sint(m.movedNormal);
      if (!math.validPoint(point) || !math.validNormal(normal)) throw frameError('moved vertex off the grid');
      edit.moving(v);
      this.#setVertex(v);
    }
  }

  /** Vertex slot v takes the values of the grid point and normal code in scratch. */
  #setVertex(v) {
    // Read the held arrays only now: adding the vertex may have grown them.
    this.math.dequantizeInto(this.point, 0, this.held.positions, 3 * v);
    this.math.decodeNormalInto(this.normal[0], this.normal[1], this.held.normals, 3 * v);
  }
}

/** The edge opposite the corner with the largest global id: edge e joins corners e and e + 1. */
function predictedEdge(held, t) {
  const { corners, vertexIds } = held;
  const c0 = vertexIds[corners[3 * t]];
  const c1 = vertexIds[corners[3 * t + 1]];
  const c2 = vertexIds[corners[3 * t + 2]];
  const newest = c0 > c1 ? (c0 > c2 ? 0 : 2) : c1 > c2 ? 1 : 2;
  return (newest + 1) % 3;
}

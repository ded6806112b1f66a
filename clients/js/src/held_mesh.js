// The mesh a client holds for one session, as version-2 deltas need it (protocol/held_mesh.cpp's
// content): triangles by id, vertices by global id (position and normal as float32 values), and
// each vertex's star (the triangles using it). A delta names held triangles and predicts new
// vertices from held ones (PROTOCOL.md 4.5).
//
// Layout: triangles and vertices live in dense slots of growable typed arrays, found by id through
// an IdIndex; a triangle's corners are vertex slots. Stars are doubly linked lists threaded through
// the corners (corner 3t + k is corner k of triangle slot t): firstCorner[v] starts vertex v's
// list, nextCorner[c] and previousCorner[c] link it, so adding or removing a triangle is O(1) and
// allocates nothing, and walking a star visits only its few corners. Slots of removed triangles
// and vertices are reused.
//
// The arrays are replaced when they grow: read them from the HeldMesh after adding, never keep them.

import { IdIndex, NONE } from './id_index.js';

export class HeldMesh {
  /** @param {number} [capacity] triangles held before the arrays first grow */
  constructor(capacity = 1024) {
    this.triangleIndex = new IdIndex(capacity);
    this.vertexIndex = new IdIndex(capacity / 2);
    this.triangleCapacity = 0;
    this.vertexCapacity = 0;
    this.#growTriangles(Math.max(4, Math.ceil(capacity)));
    this.#growVertices(Math.max(4, Math.ceil(capacity / 2)));
    this.clear();
  }

  clear() {
    this.triangleIndex.clear();
    this.vertexIndex.clear();
    this.triangleEnd = 0; // slots [0, end) have been used
    this.vertexEnd = 0;
    this.freeTriangles = [];
    this.freeVertices = [];
    /** The largest triangle id added since the last clear (a delta's new ids are above it). */
    this.maxTriangleId = -1;
  }

  get triangleCount() {
    return this.triangleIndex.size;
  }

  get vertexCount() {
    return this.vertexIndex.size;
  }

  /** The triangles, a read-only Map-like view: size, and [id, [a, b, c]] entries (global ids). */
  get triangles() {
    return { size: this.triangleCount, [Symbol.iterator]: () => this.#triangleEntries() };
  }

  /** The vertices, a read-only Map-like view: size, and [id, {position, normal}] entries. */
  get vertices() {
    return { size: this.vertexCount, [Symbol.iterator]: () => this.#vertexEntries() };
  }

  /** The corners of triangle `id` as global vertex ids, or undefined. */
  triangle(id) {
    const t = this.triangleIndex.get(id);
    return t === NONE ? undefined : this.#cornerIds(t);
  }

  /** {position: [x, y, z], normal: [x, y, z]} of vertex `id`, or undefined. */
  vertex(id) {
    const v = this.vertexIndex.get(id);
    return v === NONE ? undefined : this.#vertexValue(v);
  }

  /** The ids of the triangles using vertex `id` (empty for an unknown vertex). */
  star(id) {
    const ids = [];
    this.forEachTriangleOf(id, (triangle) => ids.push(triangle));
    return ids;
  }

  /** Calls visit(triangle id) for each triangle using vertex `id`. */
  forEachTriangleOf(id, visit) {
    const v = this.vertexIndex.get(id);
    if (v === NONE) return;
    for (let c = this.firstCorner[v]; c !== NONE; c = this.nextCorner[c]) visit(this.triangleIds[(c / 3) | 0]);
  }

  /**
   * Applies a decoded frame ({header, removed, triangleIds, mesh}, as decodeFrame or decodeDeltaV2
   * return it) in the order of PROTOCOL.md 6.2; vertices no triangle uses are dropped.
   */
  apply(frame) {
    if (frame.header.kind === 'keyframe') this.clear();
    for (const id of frame.removed) {
      const t = this.triangleIndex.get(id);
      if (t !== NONE) this.#removeAndDrop(t);
    }
    const { mesh, triangleIds } = frame;
    if (!mesh) return;
    const { globalIds, positions, normals, faces } = mesh;
    const slotOfPoint = new Int32Array(globalIds.length);
    for (let p = 0; p < globalIds.length; ++p) {
      let v = this.vertexIndex.get(globalIds[p]);
      if (v === NONE) v = this.addVertex(globalIds[p]);
      this.setVertex(v, positions, normals, 3 * p);
      slotOfPoint[p] = v;
    }
    for (let t = 0; t < triangleIds.length; ++t) {
      this.addTriangle(triangleIds[t], slotOfPoint[faces[3 * t]], slotOfPoint[faces[3 * t + 1]], slotOfPoint[faces[3 * t + 2]]);
    }
    for (let p = 0; p < globalIds.length; ++p) {
      if (this.firstCorner[slotOfPoint[p]] === NONE && this.vertexLive[slotOfPoint[p]]) this.removeVertex(slotOfPoint[p]);
    }
  }

  // ---- slots: what the version-2 decoder works with -------------------------------------------

  /** A new vertex `id` (not held) with values to be set; returns its slot. */
  addVertex(id) {
    const v = this.freeVertices.pop() ?? this.vertexEnd++;
    if (v === this.vertexCapacity) this.#growVertices(2 * this.vertexCapacity);
    this.vertexIndex.set(id, v);
    this.vertexIds[v] = id;
    this.vertexLive[v] = 1;
    this.firstCorner[v] = NONE;
    return v;
  }

  /** Sets vertex slot `v` to position from[at..at+3) and normal normalsFrom[at..at+3). */
  setVertex(v, from, normalsFrom, at) {
    const { positions, normals } = this;
    for (let k = 0; k < 3; ++k) {
      positions[3 * v + k] = from[at + k];
      normals[3 * v + k] = normalsFrom[at + k];
    }
  }

  /** Drops vertex slot `v` (no triangle uses it). */
  removeVertex(v) {
    this.vertexIndex.delete(this.vertexIds[v]);
    this.vertexLive[v] = 0;
    this.freeVertices.push(v);
  }

  /** A new triangle `id` (not held) with corners at vertex slots a, b, c; returns its slot. */
  addTriangle(id, a, b, c) {
    const t = this.freeTriangles.pop() ?? this.triangleEnd++;
    if (t === this.triangleCapacity) this.#growTriangles(2 * this.triangleCapacity);
    this.triangleIndex.set(id, t);
    this.triangleIds[t] = id;
    if (id > this.maxTriangleId) this.maxTriangleId = id;
    this.#link(3 * t, a);
    this.#link(3 * t + 1, b);
    this.#link(3 * t + 2, c);
    return t;
  }

  /** Removes triangle slot `t` from the index and its corners' stars; its vertices stay. */
  removeTriangle(t) {
    this.triangleIndex.delete(this.triangleIds[t]);
    this.triangleIds[t] = NONE;
    for (let k = 0; k < 3; ++k) this.#unlink(3 * t + k);
    this.freeTriangles.push(t);
  }

  /**
   * The slot of the triangle holding the directed edge p -> q (vertex slots), or -1; where several
   * do (a non-manifold edge), the one with the smallest id, whatever the order of the star.
   */
  holding(p, q) {
    const { corners, nextCorner, triangleIds } = this;
    let found = NONE;
    for (let c = this.firstCorner[p]; c !== NONE; c = nextCorner[c]) {
      const t = (c / 3) | 0;
      const next = c === 3 * t + 2 ? 3 * t : c + 1;
      if (corners[next] === q && (found === NONE || triangleIds[t] < triangleIds[found])) found = t;
    }
    return found;
  }

  /** {globalIds, positions, normals} of vertex slots `slots`, in that order. */
  vertexValues(slots) {
    const globalIds = new Uint32Array(slots.length);
    const positions = new Float32Array(3 * slots.length);
    const normals = new Float32Array(3 * slots.length);
    for (let i = 0; i < slots.length; ++i) {
      const v = slots[i];
      globalIds[i] = this.vertexIds[v];
      for (let k = 0; k < 3; ++k) {
        positions[3 * i + k] = this.positions[3 * v + k];
        normals[3 * i + k] = this.normals[3 * v + k];
      }
    }
    return { globalIds, positions, normals };
  }

  // ---- private ---------------------------------------------------------------------------------

  #removeAndDrop(t) {
    this.removeTriangle(t);
    for (let k = 0; k < 3; ++k) {
      const v = this.corners[3 * t + k];
      if (this.firstCorner[v] === NONE && this.vertexLive[v]) this.removeVertex(v);
    }
  }

  /** Puts corner `c` at the head of vertex v's star. */
  #link(c, v) {
    const first = this.firstCorner[v];
    this.corners[c] = v;
    this.nextCorner[c] = first;
    this.previousCorner[c] = NONE;
    if (first !== NONE) this.previousCorner[first] = c;
    this.firstCorner[v] = c;
  }

  /** Takes corner `c` out of its vertex's star. */
  #unlink(c) {
    const next = this.nextCorner[c];
    const previous = this.previousCorner[c];
    if (previous === NONE) this.firstCorner[this.corners[c]] = next;
    else this.nextCorner[previous] = next;
    if (next !== NONE) this.previousCorner[next] = previous;
  }

  #cornerIds(t) {
    const { corners, vertexIds } = this;
    return [vertexIds[corners[3 * t]], vertexIds[corners[3 * t + 1]], vertexIds[corners[3 * t + 2]]];
  }

  #vertexValue(v) {
    return { position: Array.from(this.positions.subarray(3 * v, 3 * v + 3)), normal: Array.from(this.normals.subarray(3 * v, 3 * v + 3)) };
  }

  *#triangleEntries() {
    for (let t = 0; t < this.triangleEnd; ++t) {
      if (this.triangleIds[t] !== NONE) yield [this.triangleIds[t], this.#cornerIds(t)];
    }
  }

  *#vertexEntries() {
    for (let v = 0; v < this.vertexEnd; ++v) {
      if (this.vertexLive[v]) yield [this.vertexIds[v], this.#vertexValue(v)];
    }
  }

  #growTriangles(capacity) {
    this.triangleIds = grown(Float64Array, this.triangleIds, capacity); // ids < 2^53: exact doubles
    this.corners = grown(Int32Array, this.corners, 3 * capacity);
    this.nextCorner = grown(Int32Array, this.nextCorner, 3 * capacity);
    this.previousCorner = grown(Int32Array, this.previousCorner, 3 * capacity);
    this.triangleCapacity = capacity;
  }

  #growVertices(capacity) {
    this.vertexIds = grown(Uint32Array, this.vertexIds, capacity);
    this.vertexLive = grown(Uint8Array, this.vertexLive, capacity);
    this.firstCorner = grown(Int32Array, this.firstCorner, capacity);
    this.vertexPoint = grown(Int32Array, this.vertexPoint, capacity, NONE); // scratch: DeltaEdit.result
    this.positions = grown(Float32Array, this.positions, 3 * capacity);
    this.normals = grown(Float32Array, this.normals, 3 * capacity);
    this.vertexCapacity = capacity;
  }
}

/** A typed array of `length` holding `old`'s contents first, then `fill`. */
function grown(Type, old, length, fill = 0) {
  const array = new Type(length);
  if (fill !== 0) array.fill(fill);
  if (old) array.set(old);
  return array;
}

/**
 * A HeldMesh's vertices read as a VertexTable is (SessionMesh.vertices in a version-2 session):
 * rowOf (id -> row, iterable as a Map), positions and normals (3 per row), get, has, keys, count.
 */
export class HeldVertices {
  constructor(held) {
    this.held = held;
  }

  get rowOf() {
    return this.held.vertexIndex;
  }

  get positions() {
    return this.held.positions;
  }

  get normals() {
    return this.held.normals;
  }

  get count() {
    return this.held.vertexCount;
  }

  has(id) {
    return this.held.vertexIndex.get(id) !== NONE;
  }

  /** {position, normal, uses} of vertex `id`, or undefined. */
  get(id) {
    const value = this.held.vertex(id);
    return value && { ...value, uses: this.held.star(id).length };
  }

  keys() {
    return this.held.vertexIndex.keys();
  }
}

// The changes of one version-2 delta, made in place on the held mesh with a journal to undo them
// (protocol/delta_v2_overlay.h works on an overlay of the held mesh instead: the same operations, each
// seeing the previous ones). In place, every lookup is one index probe and every star walk a few
// corners; the journal lets a delta that turns out malformed, or a decode that must leave the held
// mesh as it was, put everything back.
//
// Within the frame nothing is dropped: a held vertex whose triangles all go stays nameable until
// the end (PROTOCOL.md 4.5.2), when commit() drops every vertex no triangle uses.

import { IsomeshError } from './errors.js';
import { NONE } from './id_index.js';
import { MAX_TRIANGLE_ID } from './varint.js';

/** Vertex ids are uint32; the last one is never given (PROTOCOL.md 4.5.2). */
export const MAX_VERTEX_ID = 0xffffffff;

export class DeltaEdit {
  /** @param {import('./held_mesh.js').HeldMesh} held */
  constructor(held, baseTriangleId, baseVertexId) {
    this.held = held;
    this.base = baseTriangleId;
    this.nextTriangle = baseTriangleId;
    this.nextVertex = baseVertexId;
    this.created = []; // slot of triangle base + i, or -1 once removed again
    this.createdLive = 0;
    this.removedIds = []; // held triangles removed, and their corners (vertex slots, 3 each)
    this.removedCorners = [];
    this.newVertices = []; // slots of the vertices made, in id order
    this.moved = []; // slots of the vertices moved, and their values before (6 each)
    this.movedBefore = [];
    this.maxTriangleIdBefore = held.maxTriangleId;
    // New ids run upwards from the base: they can meet a held id only if one is at or above it
    // (never, from a server that numbers as PROTOCOL.md 4.3 says). Only then is each one checked.
    this.checkHeldIds = held.maxTriangleId >= baseTriangleId;
    this.removedAbove = this.checkHeldIds ? new Set() : null; // held ids >= base removed in this frame
  }

  triangleSlot(id) {
    return this.held.triangleIndex.get(id);
  }

  vertexSlot(id) {
    return this.held.vertexIndex.get(id);
  }

  /** The next `count` triangle ids are below 2^53 and were never held (ids are never reused). */
  checkFreshTriangleIds(count) {
    for (let k = 0; k < count; ++k) {
      const id = this.nextTriangle + k;
      if (id > MAX_TRIANGLE_ID) throw frameError('triangle ids exceed 2^53 - 1');
      if (this.checkHeldIds && this.#heldBefore(id)) throw frameError(`new triangle ${id} reuses an id`);
    }
  }

  /** A new vertex with the next id; returns its slot (values to be written by the caller). */
  newVertex() {
    const id = this.nextVertex;
    if (id === MAX_VERTEX_ID) throw frameError('vertex ids exceed 2^32 - 1');
    if (this.vertexSlot(id) !== NONE) throw frameError(`new vertex ${id} is already held`);
    const v = this.held.addVertex(id);
    this.newVertices.push(v);
    ++this.nextVertex;
    return v;
  }

  /** Records vertex slot `v`'s values before the caller moves it. */
  moving(v) {
    const { positions, normals } = this.held;
    this.moved.push(v);
    for (let k = 0; k < 3; ++k) this.movedBefore.push(positions[3 * v + k]);
    for (let k = 0; k < 3; ++k) this.movedBefore.push(normals[3 * v + k]);
  }

  /** A triangle with the next id on vertex slots a, b, c. */
  addTriangle(a, b, c) {
    this.created.push(this.held.addTriangle(this.nextTriangle++, a, b, c));
    ++this.createdLive;
  }

  removeTriangle(t) {
    const { held } = this;
    const id = held.triangleIds[t];
    if (id >= this.base && id < this.nextTriangle) {
      this.created[id - this.base] = NONE;
      --this.createdLive;
    } else {
      this.removedIds.push(id);
      this.removedCorners.push(held.corners[3 * t], held.corners[3 * t + 1], held.corners[3 * t + 2]);
      if (this.checkHeldIds && id >= this.base) this.removedAbove.add(id);
    }
    held.removeTriangle(t);
  }

  /**
   * Bisects edge e of triangle slot t (and the triangle across it) at the new vertex slot v:
   * (p, q, r) becomes (p, v, r) and (v, q, r); (q, p, s) becomes (q, v, s) and (v, p, s).
   */
  split(t, e, v) {
    const { corners } = this.held;
    const p = corners[3 * t + e];
    const q = corners[3 * t + ((e + 1) % 3)];
    const r = corners[3 * t + ((e + 2) % 3)];
    const across = this.held.holding(q, p);
    this.removeTriangle(t);
    this.addTriangle(p, v, r);
    this.addTriangle(v, q, r);
    if (across === NONE) return;
    const d = 3 * across;
    const k = corners[d] === q ? 0 : corners[d + 1] === q ? 1 : 2;
    const s = corners[d + ((k + 2) % 3)];
    this.removeTriangle(across);
    this.addTriangle(q, v, s);
    this.addTriangle(v, p, s);
  }

  /** Ends the frame: every vertex it touched that no triangle uses is dropped. */
  commit() {
    const drop = (v) => {
      if (this.held.firstCorner[v] === NONE && this.held.vertexLive[v]) this.held.removeVertex(v);
    };
    this.removedCorners.forEach(drop);
    this.newVertices.forEach(drop);
    this.moved.forEach(drop);
  }

  /** Puts the held mesh back as it was before the frame. */
  rollback() {
    const { held } = this;
    for (const t of this.created) if (t !== NONE) held.removeTriangle(t);
    for (let i = this.removedIds.length - 1; i >= 0; --i) {
      const c = this.removedCorners;
      held.addTriangle(this.removedIds[i], c[3 * i], c[3 * i + 1], c[3 * i + 2]);
    }
    for (let i = this.moved.length - 1; i >= 0; --i) {
      const v = this.moved[i];
      for (let k = 0; k < 3; ++k) {
        held.positions[3 * v + k] = this.movedBefore[6 * i + k];
        held.normals[3 * v + k] = this.movedBefore[6 * i + 3 + k];
      }
    }
    for (const v of this.newVertices) held.removeVertex(v);
    held.maxTriangleId = this.maxTriangleIdBefore;
  }

  /**
   * What the frame changed, as decodeFrame returns a version-1 delta: the held triangles removed
   * (ascending), the triangles made and still there (ascending ids), and the vertices those use
   * then the moved vertices still used, each once, in order of first use; and `moved`, the ids of
   * those moved vertices (their triangles keep their ids and now use the new values).
   */
  result(header) {
    const { held, created } = this;
    const removed = sortedIds(this.removedIds);
    const triangleIds = [];
    const faces = new Uint32Array(3 * this.createdLive);
    const listed = [];
    for (let i = 0, f = 0; i < created.length; ++i) {
      const t = created[i];
      if (t === NONE) continue;
      triangleIds.push(this.base + i);
      for (let k = 0; k < 3; ++k) faces[f++] = listPoint(held, listed, held.corners[3 * t + k]);
    }
    const moved = [];
    for (const v of this.moved) {
      if (held.firstCorner[v] === NONE) continue;
      listPoint(held, listed, v);
      moved.push(held.vertexIds[v]);
    }
    const mesh = listed.length > 0 ? { pointCount: listed.length, ...held.vertexValues(listed), faces } : null;
    for (const v of listed) held.vertexPoint[v] = NONE;
    return {
      header: { ...header, removedCount: removed.length, triangleCount: triangleIds.length },
      removed,
      triangleIds,
      mesh,
      moved,
    };
  }

  /** Whether triangle `id` (at or above the next id) was held before the frame. */
  #heldBefore(id) {
    return this.triangleSlot(id) !== NONE || this.removedAbove.has(id);
  }
}

/**
 * `ids` (triangle ids) ascending, as an Array. Sorted in a typed array (a numeric sort, and in
 * int32 while the ids allow: several times faster than Array.prototype.sort's comparator calls).
 */
function sortedIds(ids) {
  const small = ids.every((id) => id <= 0x7fffffff);
  const typed = small ? new Int32Array(ids.length) : new Float64Array(ids.length);
  for (let i = 0; i < ids.length; ++i) typed[i] = ids[i];
  typed.sort();
  const out = new Array(typed.length);
  for (let i = 0; i < typed.length; ++i) out[i] = typed[i];
  return out;
}

/** The point of vertex slot `v` in the result, listing it first if it is new there. */
function listPoint(held, listed, v) {
  if (held.vertexPoint[v] === NONE) held.vertexPoint[v] = listed.push(v) - 1;
  return held.vertexPoint[v];
}

export function frameError(message) {
  return new IsomeshError('bad_frame', message);
}

// A client's copy of one session's mesh, kept by applying decoded frames in order (PROTOCOL.md,
// "Applying frames"), stored ready to render in a TriangleSlots table.
//
// - A keyframe replaces everything.
// - A delta with the next sequence number removes its triangles, then adds its vertices (a known
//   id takes the new values) and its triangles. It is checked whole before anything changes, so an
//   inconsistent delta leaves the previous mesh on screen.
// - A delta at or before the current sequence number is stale and skipped.
// - A gap (a delta after a missing one) or an inconsistent delta stops the mesh until the next
//   keyframe, which the client asks for with `resync`.
//
// Version-2 deltas (PROTOCOL.md 4.5) are decoded here, when they are the next frame, against the
// mesh held as deltas name it (HeldMesh); a delta that does not fit it is inconsistent.
//
// Vertices (VertexTable) are reference-counted by the triangles that use them and dropped when
// unused: every payload carries all the vertices its triangles use.

import { applyDeltaV2 } from './delta_v2.js';
import { HeldMesh, HeldVertices } from './held_mesh.js';
import { IdIndex, NONE } from './id_index.js';
import { TriangleSlots } from './slots.js';

export const Outcome = Object.freeze({
  applied: 'applied',
  stale: 'stale',
  awaitingKeyframe: 'awaiting_keyframe',
  gap: 'gap',
  inconsistent: 'inconsistent',
});

/**
 * The live vertices: global id -> a row of typed arrays (position, normal, number of triangles
 * using it). Rows of dropped vertices are reused. rowOf (an IdIndex) iterates as a Map would.
 */
export class VertexTable {
  constructor(capacity = 1024) {
    this.rowOf = new IdIndex(capacity);
    this.free = [];
    this.size = 0; // rows ever used
    this.#allocate(Math.max(1, capacity));
  }

  get count() {
    return this.rowOf.size;
  }

  has(id) {
    return this.rowOf.get(id) !== NONE;
  }

  /** {position: [x, y, z], normal: [x, y, z], uses} of vertex `id`, or undefined. */
  get(id) {
    const row = this.rowOf.get(id);
    if (row === NONE) return undefined;
    const p = this.positions.subarray(3 * row, 3 * row + 3);
    const n = this.normals.subarray(3 * row, 3 * row + 3);
    return { position: Array.from(p), normal: Array.from(n), uses: this.uses[row] };
  }

  /** The ids, in no particular order (as Map.keys()). */
  keys() {
    return this.rowOf.keys();
  }

  /**
   * Sets vertex `id` to point `p` of the decoded arrays; returns 1 if a live vertex changed
   * value, else 0.
   */
  set(id, positions, normals, p) {
    let row = this.rowOf.get(id);
    if (row === NONE) {
      row = this.free.pop() ?? this.#newRow();
      this.rowOf.set(id, row);
      this.uses[row] = 0;
      this.#copy(row, positions, normals, p);
      return 0;
    }
    if (this.#same(row, positions, normals, p)) return 0;
    this.#copy(row, positions, normals, p);
    return 1;
  }

  /** One more triangle uses vertex `id` (present). */
  use(id) {
    ++this.uses[this.rowOf.get(id)];
  }

  /** One triangle fewer uses vertex `id`; the vertex is dropped when none does. */
  release(id) {
    const row = this.rowOf.get(id);
    if (--this.uses[row] === 0) {
      this.rowOf.delete(id);
      this.free.push(row);
    }
  }

  clear() {
    this.rowOf.clear();
    this.free = [];
    this.size = 0;
  }

  #newRow() {
    if (this.size === this.uses.length) this.#allocate(2 * this.uses.length);
    return this.size++;
  }

  #copy(row, positions, normals, p) {
    for (let k = 0; k < 3; ++k) {
      this.positions[3 * row + k] = positions[3 * p + k];
      this.normals[3 * row + k] = normals[3 * p + k];
    }
  }

  #same(row, positions, normals, p) {
    for (let k = 0; k < 3; ++k) {
      if (this.positions[3 * row + k] !== positions[3 * p + k] || this.normals[3 * row + k] !== normals[3 * p + k]) {
        return false;
      }
    }
    return true;
  }

  #allocate(capacity) {
    const grow = (Type, old, per) => {
      const array = new Type(capacity * per);
      if (old) array.set(old);
      return array;
    };
    this.positions = grow(Float32Array, this.positions, 3);
    this.normals = grow(Float32Array, this.normals, 3);
    this.uses = grow(Uint32Array, this.uses, 1);
  }
}

export class SessionMesh {
  /**
   * @param {{initialCapacity?: number, timing?: boolean}} [options] timing: count the time spent
   *   decoding version-2 deltas in timing.decodeV2Ms (bench/js_apply.mjs)
   */
  constructor(options = {}) {
    this.slots = new TriangleSlots(options.initialCapacity ?? 4096);
    // The live vertices (`vertices`): this table in a version-1 session; in a version-2 session the
    // held mesh's own (HeldVertices), which the decoder keeps up to date, so that no vertex is kept
    // and counted twice.
    this.table = new VertexTable((options.initialCapacity ?? 4096) / 2);
    this.vertices = this.table;
    this.synchronized = false;
    this.sequence = -1;
    this.functionVersion = 0;
    // Version 2 (PROTOCOL.md 4.5): the mesh as deltas name it, and the last keyframe's grid.
    this.held = null;
    this.grid = null;
    this.timing = options.timing ? { decodeV2Ms: 0 } : null;
  }

  get triangleCount() {
    return this.slots.count;
  }

  /**
   * Applies a frame from decodeFrame and returns an Outcome. 'gap' and 'inconsistent' mean the
   * caller should send `resync`.
   */
  apply(frame) {
    const h = frame.header;
    if (h.kind === 'keyframe') {
      this.#reset();
      this.#hold(frame);
      this.#add(frame);
      this.slots.compact();
      this.#accept(h);
      return Outcome.applied;
    }
    if (!this.synchronized) return Outcome.awaitingKeyframe;
    if (h.sequence <= this.sequence) return Outcome.stale;
    if (h.sequence !== this.sequence + 1) {
      this.synchronized = false;
      return Outcome.gap;
    }
    // A version-2 delta is decoded here, and applied to the held mesh as it is decoded. It needs no
    // consistency check: the decoder found every triangle it removes in the held mesh and gave
    // new ids no held triangle had, and the held mesh has the slot table's triangles.
    const fits = this.held ? this.#decodeV2(frame) : frame.removed !== null && this.#consistent(frame);
    if (!fits) {
      this.synchronized = false;
      return Outcome.inconsistent;
    }
    for (const id of frame.removed) this.#removeTriangle(id);
    const changed = this.#add(frame);
    this.slots.compact();
    if (changed.length > 0) this.#rewriteVertices(changed);
    this.#accept(h);
    return Outcome.applied;
  }

  /** Keeps what version-2 deltas are decoded against (nothing for version 1). */
  #hold(keyframe) {
    if (keyframe.header.version !== 2) {
      this.held = this.grid = null;
      this.vertices = this.table;
      return;
    }
    if (!this.held) {
      this.held = new HeldMesh(Math.max(this.slots.capacity, keyframe.header.triangleCount));
      this.vertices = new HeldVertices(this.held);
    }
    this.held.apply(keyframe);
    this.grid = keyframe.header.grid;
  }

  /**
   * A version-2 delta (decodeFrame left it undecoded) decoded against the held mesh, which it
   * changes: the frame gets removed, triangleIds and mesh as a version-1 delta has them. False
   * when it does not fit (the held mesh is left as it was; a resync follows).
   */
  #decodeV2(frame) {
    if (frame.header.version !== 2 || frame.removed !== null) return false; // not of this session
    const start = this.timing && performance.now();
    try {
      Object.assign(frame, applyDeltaV2(frame.header, frame.body, this.held, this.grid));
    } catch (error) {
      if (error?.code !== 'bad_frame') throw error;
      frame.error = error;
      return false;
    } finally {
      if (this.timing) this.timing.decodeV2Ms += performance.now() - start;
    }
    return true;
  }

  /** The triangles sorted by id, as {id, vertices: [a, b, c]} (for comparing meshes). */
  sortedTriangles() {
    const { slots } = this;
    const out = [];
    for (let s = 0; s < slots.count; ++s) {
      const v = slots.vertexIds.subarray(3 * s, 3 * s + 3);
      out.push({ id: slots.ids[s], vertices: [v[0], v[1], v[2]] });
    }
    return out.sort((a, b) => a.id - b.id);
  }

  /**
   * The mesh as an indexed triangle list: one entry per vertex in `vertexIds` order, and
   * `indices` (3 per triangle, in slot order) into them.
   */
  toIndexed() {
    const { slots, vertices } = this;
    const vertexIds = [...vertices.keys()].sort((a, b) => a - b);
    const index = new Map(vertexIds.map((id, i) => [id, i]));
    const positions = new Float32Array(3 * vertexIds.length);
    const normals = new Float32Array(3 * vertexIds.length);
    vertexIds.forEach((id, i) => {
      const row = vertices.rowOf.get(id);
      positions.set(vertices.positions.subarray(3 * row, 3 * row + 3), 3 * i);
      normals.set(vertices.normals.subarray(3 * row, 3 * row + 3), 3 * i);
    });
    const indices = new Uint32Array(3 * slots.count);
    for (let c = 0; c < indices.length; ++c) indices[c] = index.get(slots.vertexIds[c]);
    return { vertexIds: Uint32Array.from(vertexIds), positions, normals, indices };
  }

  #accept(header) {
    this.synchronized = true;
    this.sequence = header.sequence;
    this.functionVersion = header.functionVersion;
  }

  #reset() {
    this.slots.clear();
    this.table.clear();
  }

  /** Every removed id is present, and every added id is absent once the removals are done. */
  #consistent(frame) {
    const { slots } = this;
    if (!frame.removed.every((id) => slots.has(id))) return false;
    const removed = frame.removed.length > 0 ? new Set(frame.removed) : null;
    return frame.triangleIds.every((id) => !slots.has(id) || (removed !== null && removed.has(id)));
  }

  #removeTriangle(id) {
    const { slots, table } = this;
    const slot = slots.slotOf(id);
    if (this.vertices === table) for (let k = 0; k < 3; ++k) table.release(slots.vertexIds[3 * slot + k]);
    slots.release(id);
  }

  /**
   * Adds the frame's vertices and triangles; returns the ids of live vertices whose values changed
   * (in a version-2 session, the moved vertices the decoder names).
   */
  #add(frame) {
    const { mesh, triangleIds } = frame;
    const { table, slots } = this;
    const counted = this.vertices === table;
    const changed = counted ? [] : frame.moved ?? [];
    if (!mesh) return changed;
    const { globalIds, positions, normals, faces } = mesh;
    if (counted) {
      for (let p = 0; p < globalIds.length; ++p) if (table.set(globalIds[p], positions, normals, p)) changed.push(globalIds[p]);
    }
    for (let t = 0; t < triangleIds.length; ++t) {
      const slot = slots.insert(triangleIds[t]);
      for (let k = 0; k < 3; ++k) {
        const p = faces[3 * t + k];
        const id = globalIds[p];
        if (counted) table.use(id);
        slots.write(slot, k, id, positions[3 * p], positions[3 * p + 1], positions[3 * p + 2],
          normals[3 * p], normals[3 * p + 1], normals[3 * p + 2]);
      }
    }
    return changed;
  }

  /**
   * A delta gave known vertices new values (a version-2 move, or a version-1 delta re-sending
   * them): rewrite the corners that use them. The held mesh names those triangles in its stars;
   * without one every corner is looked at (O(n)).
   */
  #rewriteVertices(changed) {
    const { slots, held } = this;
    if (held) {
      for (const id of changed) {
        const row = this.vertices.rowOf.get(id);
        held.forEachTriangleOf(id, (triangle) => this.#rewriteCorner(slots.slotOf(triangle), id, row));
      }
      return;
    }
    const ids = new Set(changed);
    for (let s = 0; s < slots.count; ++s) {
      for (let k = 0; k < 3; ++k) {
        const id = slots.vertexIds[3 * s + k];
        if (ids.has(id)) this.#rewriteCorner(s, id, this.vertices.rowOf.get(id));
      }
    }
  }

  /** The corner of slot `s` at vertex `id` takes the values of vertex row `row`. */
  #rewriteCorner(s, id, row) {
    const { slots } = this;
    const { positions: p, normals: n } = this.vertices;
    const r = 3 * row;
    for (let k = 0; k < 3; ++k) {
      if (slots.vertexIds[3 * s + k] === id) slots.write(s, k, id, p[r], p[r + 1], p[r + 2], n[r], n[r + 1], n[r + 2]);
    }
    slots.touch(s);
  }
}

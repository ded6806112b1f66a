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
// Vertices are reference-counted by the triangles that use them and dropped when unused: every
// payload carries all the vertices its triangles use.

import { TriangleSlots } from './slots.js';

export const Outcome = Object.freeze({
  applied: 'applied',
  stale: 'stale',
  awaitingKeyframe: 'awaiting_keyframe',
  gap: 'gap',
  inconsistent: 'inconsistent',
});

export class SessionMesh {
  /** @param {{initialCapacity?: number}} [options] */
  constructor(options = {}) {
    this.slots = new TriangleSlots(options.initialCapacity ?? 4096);
    /** Global vertex id -> {position: [x, y, z], normal: [x, y, z], uses}. */
    this.vertices = new Map();
    this.synchronized = false;
    this.sequence = -1;
    this.functionVersion = 0;
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
    if (!this.#consistent(frame)) {
      this.synchronized = false;
      return Outcome.inconsistent;
    }
    for (const id of frame.removed) this.#removeTriangle(id);
    const changed = this.#add(frame);
    this.slots.compact();
    if (changed.size > 0) this.#rewriteVertices(changed);
    this.#accept(h);
    return Outcome.applied;
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
    const { slots } = this;
    const vertexIds = [...this.vertices.keys()].sort((a, b) => a - b);
    const index = new Map(vertexIds.map((id, i) => [id, i]));
    const positions = new Float32Array(3 * vertexIds.length);
    const normals = new Float32Array(3 * vertexIds.length);
    vertexIds.forEach((id, i) => {
      const v = this.vertices.get(id);
      positions.set(v.position, 3 * i);
      normals.set(v.normal, 3 * i);
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
    this.vertices.clear();
  }

  /** Every removed id is present, and every added id is absent once the removals are done. */
  #consistent(frame) {
    const { slots } = this;
    if (!frame.removed.every((id) => slots.has(id))) return false;
    const removed = frame.removed.length > 0 ? new Set(frame.removed) : null;
    return frame.triangleIds.every((id) => !slots.has(id) || (removed !== null && removed.has(id)));
  }

  #removeTriangle(id) {
    const { slots } = this;
    const slot = slots.slotOf(id);
    for (let k = 0; k < 3; ++k) {
      const vertexId = slots.vertexIds[3 * slot + k];
      const vertex = this.vertices.get(vertexId);
      if (--vertex.uses === 0) this.vertices.delete(vertexId);
    }
    slots.release(id);
  }

  /** Adds the frame's vertices and triangles; returns the ids of live vertices whose values changed. */
  #add(frame) {
    const changed = new Set();
    const { mesh, triangleIds } = frame;
    if (!mesh) return changed;
    const { globalIds, positions, normals, faces } = mesh;
    for (let p = 0; p < globalIds.length; ++p) {
      const id = globalIds[p];
      const position = [positions[3 * p], positions[3 * p + 1], positions[3 * p + 2]];
      const normal = [normals[3 * p], normals[3 * p + 1], normals[3 * p + 2]];
      const known = this.vertices.get(id);
      if (!known) {
        this.vertices.set(id, { position, normal, uses: 0 });
      } else if (!sameValues(known, position, normal)) {
        known.position = position;
        known.normal = normal;
        changed.add(id);
      }
    }
    const { slots } = this;
    for (let t = 0; t < triangleIds.length; ++t) {
      const slot = slots.insert(triangleIds[t]);
      for (let k = 0; k < 3; ++k) {
        const p = faces[3 * t + k];
        const id = globalIds[p];
        ++this.vertices.get(id).uses;
        slots.write(slot, k, id, positions[3 * p], positions[3 * p + 1], positions[3 * p + 2],
          normals[3 * p], normals[3 * p + 1], normals[3 * p + 2]);
      }
    }
    return changed;
  }

  /** A delta re-sent known vertices with new values: rewrite the corners that use them (rare: O(n)). */
  #rewriteVertices(changed) {
    const { slots } = this;
    for (let s = 0; s < slots.count; ++s) {
      for (let k = 0; k < 3; ++k) {
        const id = slots.vertexIds[3 * s + k];
        if (!changed.has(id)) continue;
        const { position: p, normal: n } = this.vertices.get(id);
        slots.write(s, k, id, p[0], p[1], p[2], n[0], n[1], n[2]);
        slots.touch(s);
      }
    }
  }
}

function sameValues(vertex, position, normal) {
  const p = vertex.position;
  const n = vertex.normal;
  return p[0] === position[0] && p[1] === position[1] && p[2] === position[2] &&
    n[0] === normal[0] && n[1] === normal[1] && n[2] === normal[2];
}

// Version-2 deltas (PROTOCOL.md 4.5.2): a 56-byte header and one range-coded body, decoded
// against the mesh the client holds. A port of the decoder of protocol/delta_v2.cpp: splits of
// held edges (new vertices predicted from the split edge), explicit removals, loose vertices,
// explicit triangles, moved vertices. The result has the shape of decodeFrame's, so a
// SessionMesh applies it as a version-1 delta.

import { IsomeshError } from './errors.js';
import { GridMath } from './delta_v2_geometry.js';
import { RangeDecoder, bitModel, intModel } from './range_decoder.js';
import { MAX_TRIANGLE_ID } from './varint.js';

export const DELTA_V2_HEADER_BYTES = 56;
const MAX_CHANGES = 2 ** 22;
const MAX_VERTEX_ID = 0xffffffff;

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

/** The edge opposite the corner with the largest global id: edge e joins corners e and e + 1. */
function predictedEdge(c) {
  const newest = c[0] > c[1] ? (c[0] > c[2] ? 0 : 2) : c[1] > c[2] ? 1 : 2;
  return (newest + 1) % 3;
}

/** The held mesh with a delta's changes on top (protocol/delta_v2.cpp's Overlay). */
class Overlay {
  constructor(held) {
    this.held = held;
    this.created = new Map();
    this.removed = new Set();
    this.stars = new Map();
    this.vertices = new Map();
  }

  triangle(id) {
    const made = this.created.get(id);
    if (made) return made;
    if (this.removed.has(id)) return undefined;
    return this.held.triangle(id);
  }

  vertex(id) {
    return this.vertices.get(id) ?? this.held.vertex(id);
  }

  star(v) {
    return this.stars.get(v) ?? this.held.star(v);
  }

  /** The triangle holding the directed edge p -> q; of several, the smallest id. */
  holding(p, q) {
    let found;
    for (const id of this.star(p)) {
      const c = this.triangle(id);
      for (let k = 0; k < 3; ++k) {
        if (c[k] === p && c[(k + 1) % 3] === q && (found === undefined || id < found)) found = id;
      }
    }
    return found;
  }

  remove(id) {
    for (const v of this.triangle(id)) {
      const star = this.#starMut(v);
      star.splice(star.indexOf(id), 1);
    }
    if (!this.created.delete(id)) this.removed.add(id);
  }

  add(id, c) {
    this.created.set(id, c);
    for (const v of c) this.#starMut(v).push(id);
  }

  /** (p, q, r) -> (p, v, r), (v, q, r); the triangle across, (q, p, s) -> (q, v, s), (v, p, s). */
  split(t, e, v, nextId) {
    const c = this.triangle(t);
    const [p, q, r] = [c[e], c[(e + 1) % 3], c[(e + 2) % 3]];
    const across = this.holding(q, p);
    this.remove(t);
    this.add(nextId++, [p, v, r]);
    this.add(nextId++, [v, q, r]);
    if (across === undefined) return nextId;
    const d = this.triangle(across);
    const k = d[0] === q ? 0 : d[1] === q ? 1 : 2;
    const s = d[(k + 2) % 3];
    this.remove(across);
    this.add(nextId++, [q, v, s]);
    this.add(nextId++, [v, p, s]);
    return nextId;
  }

  /** Whether triangle `id` was held or made in this frame (ids are never reused). */
  used(id) {
    return this.created.has(id) || this.held.triangle(id) !== undefined;
  }

  #starMut(v) {
    let star = this.stars.get(v);
    if (!star) {
      star = [...this.held.star(v)];
      this.stars.set(v, star);
    }
    return star;
  }
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
 */
export function decodeDeltaV2(header, body, held, grid) {
  const state = {
    math: new GridMath(grid),
    overlay: new Overlay(held),
    coder: new RangeDecoder(body),
    models: models(),
    nextTriangle: header.baseTriangleId,
    nextVertex: header.baseVertexId,
    moved: [],
  };
  splits(state);
  removals(state);
  looseVertices(state);
  triangles(state);
  moved(state);
  return result(header, state);
}

function count(state) {
  const n = state.coder.uint(state.models.count);
  if (n > MAX_CHANGES) throw frameError('more than 2^22 changes in one frame');
  return n;
}

function newVertexId(state) {
  if (state.nextVertex === MAX_VERTEX_ID) throw frameError('vertex ids exceed 2^32 - 1');
  if (state.overlay.vertex(state.nextVertex)) throw frameError(`new vertex ${state.nextVertex} is already held`);
  return state.nextVertex++;
}

/** A triangle id the frame may give: below 2^53 and never used before. */
function freshTriangleId(state, id) {
  if (id > MAX_TRIANGLE_ID) throw frameError('triangle ids exceed 2^53 - 1');
  if (state.overlay.used(id)) throw frameError(`new triangle ${id} reuses an id`);
}

function splits(state) {
  const { coder, models: m, overlay, math } = state;
  const rounds = count(state);
  let total = 0;
  for (let round = 0; round < rounds; ++round) {
    const n = count(state);
    if ((total += n) > MAX_CHANGES) throw frameError('more than 2^22 splits');
    let previous = 0;
    for (let i = 0; i < n; ++i) {
      const t = previous + coder.uint(m.splitGap) + (i === 0 ? 0 : 1);
      if (t > MAX_TRIANGLE_ID) throw frameError('bad split triangle id');
      previous = t;
      const c = overlay.triangle(t);
      if (!c) throw frameError(`split of triangle ${t}, not held`);
      let miss = coder.bit(m.edgeMiss);
      if (miss !== 0 && coder.bit(m.edgeSecond)) miss = 2;
      const e = (predictedEdge(c) + miss) % 3;
      const a = overlay.vertex(c[e]);
      const b = overlay.vertex(c[(e + 1) % 3]);
      const q = math.predictSplit(math.recover(a.position), math.recover(b.position), a.normal, b.normal);
      for (let axis = 0; axis < 3; ++axis) q[axis] += coder.sint(m.position);
      const normal = math.predictNormal(a.normal, b.normal);
      for (let k = 0; k < 2; ++k) normal[k] += coder.sint(m.normal);
      if (!math.validPoint(q) || !math.validNormal(normal)) throw frameError('split vertex off the grid');
      const id = newVertexId(state);
      for (let k = 0; k < 4; ++k) freshTriangleId(state, state.nextTriangle + k);
      overlay.vertices.set(id, { position: math.dequantize(q), normal: math.decodeNormal(normal) });
      state.nextTriangle = overlay.split(t, e, id, state.nextTriangle);
    }
  }
}

function removals(state) {
  const { coder, models: m, overlay } = state;
  const n = count(state);
  let previous = 0;
  for (let i = 0; i < n; ++i) {
    const id = previous + coder.uint(m.removedGap) + (i === 0 ? 0 : 1);
    previous = id;
    if (!overlay.triangle(id)) throw frameError(`removes triangle ${id}, not held`);
    overlay.remove(id);
  }
}

function looseVertices(state) {
  const { coder, overlay, math } = state;
  const n = count(state);
  const { positionBits, normalBits } = math.grid;
  for (let i = 0; i < n; ++i) {
    const q = [0, 1, 2].map(() => coder.direct(positionBits));
    const normal = [0, 1].map(() => coder.direct(normalBits) - math.maxOctahedral);
    if (!math.validPoint(q) || !math.validNormal(normal)) throw frameError('loose vertex off the grid');
    const id = newVertexId(state);
    overlay.vertices.set(id, { position: math.dequantize(q), normal: math.decodeNormal(normal) });
  }
}

function triangles(state) {
  const { coder, models: m, overlay } = state;
  const n = count(state);
  let last = 0;
  for (let i = 0; i < n; ++i) {
    const c = [0, 0, 0];
    for (let k = 0; k < 3; ++k) {
      const id = last + coder.sint(m.vertexStep);
      if (id < 0 || id > MAX_VERTEX_ID) throw frameError('bad vertex id');
      c[k] = last = id;
      if (!overlay.vertex(id)) throw frameError(`a triangle uses unknown vertex ${id}`);
    }
    if (c[0] === c[1] || c[1] === c[2] || c[0] === c[2]) throw frameError('a triangle repeats a vertex');
    freshTriangleId(state, state.nextTriangle);
    overlay.add(state.nextTriangle++, c);
  }
}

function moved(state) {
  const { coder, models: m, overlay, math } = state;
  const n = count(state);
  const maxOffset = 2 * math.maxCoordinate + 2;
  let previous = 0;
  let offset = 0;
  for (let i = 0; i < n; ++i) {
    const id = previous + coder.uint(m.movedGap) + (i === 0 ? 0 : 1);
    if (id > MAX_VERTEX_ID) throw frameError('bad moved vertex id');
    previous = id;
    const held = overlay.vertex(id);
    if (!held) throw frameError(`moves vertex ${id}, not held`);
    // Along the held normal, by the previous moved vertex's offset plus a residual (4.5.2, 5).
    offset += coder.sint(m.movedOffset);
    if (Math.abs(offset) > maxOffset) throw frameError('moved vertex offset out of range');
    const q = math.predictMove(math.recover(held.position), held.normal, offset);
    const normal = math.encodeNormal(held.normal);
    for (let axis = 0; axis < 3; ++axis) q[axis] += coder.sint(m.movedPosition);
    for (let k = 0; k < 2; ++k) normal[k] += coder.sint(m.movedNormal);
    if (!math.validPoint(q) || !math.validNormal(normal)) throw frameError('moved vertex off the grid');
    overlay.vertices.set(id, { position: math.dequantize(q), normal: math.decodeNormal(normal) });
    state.moved.push(id);
  }
}

/** What applying the delta changes, as decodeFrame returns a version-1 delta. */
function result(header, { overlay, moved: movedIds }) {
  const removed = [...overlay.removed].sort((a, b) => a - b);
  const added = [...overlay.created.keys()].sort((a, b) => a - b);
  const point = new Map();
  const globalIds = [];
  const list = (v) => {
    if (!point.has(v)) {
      point.set(v, globalIds.length);
      globalIds.push(v);
    }
  };
  const faces = new Uint32Array(3 * added.length);
  added.forEach((id, t) => {
    overlay.created.get(id).forEach((v, k) => {
      list(v);
      faces[3 * t + k] = point.get(v);
    });
  });
  // A moved vertex whose triangles are all gone is dropped, not listed.
  for (const v of movedIds) if (overlay.star(v).length > 0) list(v);
  const positions = new Float32Array(3 * globalIds.length);
  const normals = new Float32Array(3 * globalIds.length);
  const values = globalIds.map((v, p) => {
    const value = overlay.vertex(v);
    positions.set(value.position, 3 * p);
    normals.set(value.normal, 3 * p);
    return value;
  });
  const mesh = added.length > 0 || globalIds.length > 0
    ? { pointCount: globalIds.length, globalIds: Uint32Array.from(globalIds), positions, normals, faces, values }
    : null;
  return {
    header: { ...header, removedCount: removed.length, triangleCount: added.length },
    removed,
    triangleIds: added,
    mesh,
    moved: movedIds, // the ids of the vertices the delta moved (PROTOCOL.md 4.5.2, step 5)
  };
}

function frameError(message) {
  return new IsomeshError('bad_frame', message);
}

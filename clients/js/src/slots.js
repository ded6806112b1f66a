// The triangle slot table: the thesis's "display list" (section 4.2), triangles and their normals in
// one coherent buffer with constant-time insertion, deletion and access.
//
// Slot s holds one triangle: 9 floats of corner positions at positions[9s..9s+8], 9 floats of
// corner normals at normals[9s..9s+8], its 3 global vertex ids at vertexIds[3s..3s+2] and its wire
// id at ids[s]. Live triangles always occupy slots [0, count) once compact() has run, so a renderer
// draws the first 3 * count vertices of the arrays, uploaded in place (non-indexed geometry).
//
// Deleting is split in two so that a delta moves as little data as possible: release(id) makes a
// hole (O(1)), insert(id) fills a hole or appends (O(1)), and compact() moves the last live
// triangles into the holes that remain (O(h log h) for h holes). A refinement delta removes two
// triangles per split and adds four, so most new triangles land in freed slots and few move.
//
// Writes are recorded as dirty slots; takeDirtyRanges() hands them to the renderer as a few
// coalesced ranges to upload. Growing the arrays (doubling) replaces them: `generation` counts
// reallocations so a renderer knows when to rebind its buffers.

import { IdIndex, NONE } from './id_index.js';

const FLOATS = 9; // 3 corners x 3 components
const HOLE = -1;
const MAX_RANGES = 32;

export class TriangleSlots {
  /** @param {number} [initialCapacity] triangles the arrays hold before they first grow */
  constructor(initialCapacity = 1024) {
    this.capacity = 0;
    this.generation = 0;
    this.positions = new Float32Array(0);
    this.normals = new Float32Array(0);
    this.vertexIds = new Uint32Array(0);
    this.ids = new Float64Array(0); // wire ids are < 2^53: exact in a double; HOLE marks a hole
    this.end = 0; // slots [0, end) are live or holes
    this.holes = [];
    this.slotOfId = new IdIndex(initialCapacity);
    this.dirty = [];
    this.#reserve(Math.max(1, initialCapacity));
  }

  /** Live triangles. */
  get count() {
    return this.end - this.holes.length;
  }

  has(id) {
    return this.slotOfId.get(id) !== NONE;
  }

  /** The slot of triangle `id`, or undefined. */
  slotOf(id) {
    const slot = this.slotOfId.get(id);
    return slot === NONE ? undefined : slot;
  }

  /**
   * Adds triangle `id` (not present) and returns its slot, whose 9 position floats, 9 normal
   * floats and 3 vertex ids the caller then writes (see write()).
   */
  insert(id) {
    if (this.has(id)) throw new Error(`triangle ${id} is already present`);
    let slot = this.holes.pop();
    if (slot === undefined) {
      if (this.end === this.capacity) this.#reserve(2 * this.capacity);
      slot = this.end++;
    }
    this.ids[slot] = id;
    this.slotOfId.set(id, slot);
    this.dirty.push(slot);
    return slot;
  }

  /** Writes corner `corner` (0..2) of `slot`: vertex id, position and normal. */
  write(slot, corner, vertexId, px, py, pz, nx, ny, nz) {
    const f = FLOATS * slot + 3 * corner;
    this.positions[f] = px;
    this.positions[f + 1] = py;
    this.positions[f + 2] = pz;
    this.normals[f] = nx;
    this.normals[f + 1] = ny;
    this.normals[f + 2] = nz;
    this.vertexIds[3 * slot + corner] = vertexId;
  }

  /** Marks `slot` for upload after its contents changed in place. */
  touch(slot) {
    this.dirty.push(slot);
  }

  /** Makes triangle `id`'s slot a hole; returns false if `id` is not present. Call compact() after. */
  release(id) {
    const slot = this.slotOfId.get(id);
    if (slot === NONE) return false;
    this.slotOfId.delete(id);
    this.ids[slot] = HOLE;
    this.holes.push(slot);
    return true;
  }

  /** Deletes triangle `id` at once: release then compact. */
  remove(id) {
    const found = this.release(id);
    if (found) this.compact();
    return found;
  }

  /** Moves the last live triangles into the holes, so that live slots are exactly [0, count). */
  compact() {
    const holes = this.holes.sort((a, b) => a - b);
    let low = 0;
    let high = holes.length - 1;
    while (low <= high) {
      const last = this.end - 1;
      if (holes[high] === last) {
        --high; // the last slot is itself a hole: drop it
      } else {
        this.#move(last, holes[low++]);
      }
      this.end = last;
    }
    this.holes = [];
  }

  clear() {
    this.slotOfId.clear();
    this.holes = [];
    this.end = 0;
    this.dirty = [];
    this.ids.fill(HOLE);
  }

  /**
   * The slot ranges written since the last call, coalesced into at most 32 ranges
   * [{start, count}] in slots, ascending, within [0, count). Clears the record.
   */
  takeDirtyRanges() {
    const live = this.count;
    const slots = this.dirty.filter((s) => s < live).sort((a, b) => a - b);
    this.dirty = [];
    if (slots.length === 0) return [];
    const gaps = [];
    for (let i = 1; i < slots.length; ++i) gaps.push(slots[i] - slots[i - 1]);
    // Merge across the largest gap that still leaves at most MAX_RANGES ranges.
    const sortedGaps = gaps.filter((g) => g > 1).sort((a, b) => b - a);
    const threshold = sortedGaps.length >= MAX_RANGES ? sortedGaps[MAX_RANGES - 1] : 1;
    const ranges = [];
    let start = slots[0];
    for (let i = 1; i <= slots.length; ++i) {
      if (i === slots.length || slots[i] - slots[i - 1] > threshold) {
        ranges.push({ start, count: slots[i - 1] - start + 1 });
        if (i < slots.length) start = slots[i];
      }
    }
    return ranges;
  }

  /** Checks the table's invariants (for tests); throws on the first violation. */
  checkInvariants() {
    if (this.holes.length !== 0) throw new Error('holes remain: call compact()');
    if (this.slotOfId.size !== this.end) throw new Error('slot map size differs from count');
    for (let s = 0; s < this.end; ++s) {
      if (this.slotOfId.get(this.ids[s]) !== s) throw new Error(`slot ${s} is not mapped back`);
    }
  }

  #move(from, to) {
    const id = this.ids[from];
    this.positions.copyWithin(FLOATS * to, FLOATS * from, FLOATS * from + FLOATS);
    this.normals.copyWithin(FLOATS * to, FLOATS * from, FLOATS * from + FLOATS);
    this.vertexIds.copyWithin(3 * to, 3 * from, 3 * from + 3);
    this.ids[to] = id;
    this.ids[from] = HOLE;
    this.slotOfId.set(id, to);
    this.dirty.push(to);
  }

  #reserve(capacity) {
    const grow = (Type, old, per) => {
      const array = new Type(capacity * per);
      array.set(old);
      return array;
    };
    this.positions = grow(Float32Array, this.positions, FLOATS);
    this.normals = grow(Float32Array, this.normals, FLOATS);
    this.vertexIds = grow(Uint32Array, this.vertexIds, 3);
    const ids = new Float64Array(capacity).fill(HOLE);
    ids.set(this.ids);
    this.ids = ids;
    this.capacity = capacity;
    ++this.generation;
  }
}

// A three.js BufferGeometry over a TriangleSlots table (clients/js/src/slots.js): the session's
// mesh lives in GPU buffers that are updated in place.
//
// The slot table's position and normal arrays are the attributes' arrays themselves (no copy).
// After each batch of frames, sync() uploads only the slot ranges the frames wrote
// (BufferAttribute update ranges: one bufferSubData per range) and sets the draw range to the
// live triangles. three.js clears the ranges once it has uploaded them.
// Only when the table grows (doubling: O(log n) times per session) are the GPU
// buffers replaced.

import { BufferAttribute, BufferGeometry, DynamicDrawUsage } from 'three';

const FLOATS_PER_SLOT = 9;

export class SlotGeometry {
  constructor() {
    this.geometry = new BufferGeometry();
    this.slots = null;
    this.generation = -1;
    /** Floats uploaded by the last sync (for the status line and tests). */
    this.uploadedFloats = 0;
    /** Floats uploaded in place (update ranges) since the start, and GPU buffers made anew. */
    this.totalRangeFloats = 0;
    this.rebinds = 0;
  }

  /** Shows `slots` (a TriangleSlots) from now on. */
  attach(slots) {
    this.slots = slots;
    this.generation = -1;
    this.sync();
  }

  /** Shows nothing (the surface has no session). */
  detach() {
    this.slots = null;
    this.geometry.setDrawRange(0, 0);
  }

  /** Uploads what changed since the last call; returns true when anything did. */
  sync() {
    const { slots, geometry } = this;
    if (!slots) return false;
    let changed = false;
    if (slots.generation !== this.generation) {
      this.#rebind();
      slots.takeDirtyRanges();
      this.uploadedFloats = 2 * slots.count * FLOATS_PER_SLOT;
      changed = true;
    } else {
      const ranges = slots.takeDirtyRanges();
      this.uploadedFloats = 0;
      if (ranges.length > 0) {
        for (const name of ['position', 'normal']) {
          const attribute = geometry.getAttribute(name);
          for (const { start, count } of ranges) {
            attribute.addUpdateRange(start * FLOATS_PER_SLOT, count * FLOATS_PER_SLOT);
            this.uploadedFloats += count * FLOATS_PER_SLOT;
            this.totalRangeFloats += count * FLOATS_PER_SLOT;
          }
          attribute.needsUpdate = true;
        }
        changed = true;
      }
    }
    const vertices = 3 * slots.count;
    if (geometry.drawRange.count !== vertices) {
      geometry.setDrawRange(0, vertices);
      changed = true;
    }
    return changed;
  }

  /** New arrays (the table grew): new GPU buffers, uploaded whole once. */
  #rebind() {
    const { slots, geometry } = this;
    geometry.dispose(); // frees the old GPU buffers; the renderer re-creates them on next draw
    for (const [name, array] of [['position', slots.positions], ['normal', slots.normals]]) {
      const attribute = new BufferAttribute(array, 3);
      attribute.setUsage(DynamicDrawUsage);
      geometry.setAttribute(name, attribute);
    }
    this.generation = slots.generation;
    ++this.rebinds;
  }
}

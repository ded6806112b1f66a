// Wire ids to dense slots: an open-addressing hash table (linear probing, backward-shift deletion)
// in two typed arrays. The held mesh looks a triangle or vertex up by id
// once per name a frame carries and works on slots after that.
//
// Why not a Map: ids are integers below 2^53 that the server hands out in ascending runs, so a
// multiplicative hash spreads them evenly, and a table of doubles and int32s costs no allocation
// per entry and no garbage when entries go (a refinement frame removes and adds thousands).
// Why not an array indexed by id: the ids of a long session grow without bound (never reused)
// while the live ones stay a window of them; this table's size follows the live count.

/** No slot: what get() returns for an id not in the index. */
export const NONE = -1;
const EMPTY = NONE; // a free entry holds no slot
const TWO_32 = 2 ** 32;
const BLOCK_BITS = 4;
const BLOCK = 2 ** BLOCK_BITS;
const MIN_BITS = BLOCK_BITS + 2;

export class IdIndex {
  /** @param {number} [capacity] entries held before the table first grows */
  constructor(capacity = 16) {
    this.#allocate(Math.max(MIN_BITS, Math.ceil(Math.log2(2 * Math.max(1, capacity)))));
  }

  /** The slot of `id`, or NONE (-1). */
  get(id) {
    const { ids, values, mask } = this;
    for (let i = this.#home(id); ; i = (i + 1) & mask) {
      const value = values[i];
      if (value === EMPTY || ids[i] === id) return value;
    }
  }

  /** Maps `id` to `slot` (>= 0), replacing any slot it had. */
  set(id, slot) {
    if (2 * (this.size + 1) > this.values.length) this.#grow();
    const { ids, values, mask } = this;
    let i = this.#home(id);
    while (values[i] !== EMPTY && ids[i] !== id) i = (i + 1) & mask;
    if (values[i] === EMPTY) ++this.size;
    ids[i] = id;
    values[i] = slot;
  }

  /** Forgets `id`; returns whether it was there. */
  delete(id) {
    const { ids, values, mask } = this;
    let i = this.#home(id);
    while (values[i] !== EMPTY && ids[i] !== id) i = (i + 1) & mask;
    if (values[i] === EMPTY) return false;
    // Backward shift: move later entries of the probe run into the gap when their home allows,
    // so that lookups never need tombstones.
    for (let j = (i + 1) & mask; values[j] !== EMPTY; j = (j + 1) & mask) {
      const home = this.#home(ids[j]);
      if (((j - home) & mask) >= ((j - i) & mask)) {
        ids[i] = ids[j];
        values[i] = values[j];
        i = j;
      }
    }
    values[i] = EMPTY;
    --this.size;
    return true;
  }

  /** [id, slot] pairs, in no particular order (as a Map's entries). */
  *[Symbol.iterator]() {
    const { ids, values } = this;
    for (let i = 0; i < values.length; ++i) if (values[i] !== EMPTY) yield [ids[i], values[i]];
  }

  /** The ids, in no particular order. */
  *keys() {
    for (const [id] of this) yield id;
  }

  clear() {
    if (this.size === 0) return;
    this.values.fill(EMPTY);
    this.size = 0;
  }

  /**
   * Where `id`'s probe starts: runs of BLOCK consecutive ids hash together and keep their order,
   * so that the ids a frame names together (the server hands them out in ascending runs) share
   * cache lines; the runs are spread by Fibonacci hashing.
   */
  #home(id) {
    const low = id >>> 0; // the low 32 bits, mixed with the high ones past 2^32
    const high = id < TWO_32 ? 0 : Math.imul((id - low) / TWO_32, 0x85ebca6b);
    const run = Math.imul((low >>> BLOCK_BITS) ^ high, 0x9e3779b1) >>> this.shift;
    return (run << BLOCK_BITS) | (low & (BLOCK - 1));
  }

  #grow() {
    const { ids, values } = this;
    this.#allocate(this.bits + 1);
    for (let i = 0; i < values.length; ++i) if (values[i] !== EMPTY) this.set(ids[i], values[i]);
  }

  #allocate(bits) {
    this.bits = bits;
    this.shift = 32 - (bits - BLOCK_BITS);
    this.mask = 2 ** bits - 1;
    this.ids = new Float64Array(2 ** bits);
    this.values = new Int32Array(2 ** bits).fill(EMPTY);
    this.size = 0;
  }
}

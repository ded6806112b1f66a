// Applies received mesh frames a few milliseconds at a time, so that decoding never freezes the
// page, however fast refinement streams.
//
// Visible page: once per animation frame, before rendering, frames are applied until a time
// budget is spent (BUDGET_MS; BACKLOG_BUDGET_MS while a backlog builds up, so the mesh catches up
// without a long frame). When drawing itself is slow (a software GPU draws 200,000 triangles in
// about half a second), the budget grows to a quarter of the time between animation frames, never
// above SLOW_BUDGET_MS: the frame rate barely changes and the mesh does not fall far behind. The
// rest waits for the next animation frame.
//
// Hidden page (no animation frames): a background loop applies frames in slices of the same
// budget, yielding to the event loop between slices through a message channel (not throttled
// like timers), and polls for new frames with a timer while nothing is queued. It never applies
// everything at once: the old 200 ms fallback timer that did so caused freezes of up to 0.9 s
// whenever animation frames were slow.

export const BUDGET_MS = 6;
export const BACKLOG_BUDGET_MS = 12;
export const BACKLOG_FRAMES = 32;
export const HIDDEN_POLL_MS = 250;
export const SLOW_BUDGET_MS = 24;
const SLOW_SHARE = 0.25;

export class FramePump {
  /**
   * @param {object} options
   * @param {(deadline: number) => void} options.drain applies frames until performance.now() passes
   *   `deadline` (at least one; IsomeshClient.drainFrames)
   * @param {() => number} options.pending frames waiting
   * @param {() => boolean} [options.isHidden] default: document.visibilityState === 'hidden'
   * @param {() => number} [options.now]
   * @param {(fn: Function) => void} [options.yieldTask] runs `fn` in a later task
   * @param {(fn: Function, ms: number) => void} [options.setTimer]
   */
  constructor({ drain, pending, isHidden, now, yieldTask, setTimer }) {
    this.drain = drain;
    this.pending = pending;
    this.isHidden = isHidden ?? (() => document.visibilityState === 'hidden');
    this.now = now ?? (() => performance.now());
    this.yieldTask = yieldTask ?? messageChannelTask();
    this.setTimer = setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.hiddenLoop = false;
    this.lastFrameAt = null;
    this.frameInterval = 16; // smoothed time between animation frames, ms
    /** Longest slice spent applying frames, in ms (for tests and the console). */
    this.longestSliceMs = 0;
  }

  /** The visible path: call once per animation frame; returns true when frames were applied. */
  onAnimationFrame() {
    const now = this.now();
    if (this.lastFrameAt !== null) this.frameInterval += 0.3 * (Math.min(now - this.lastFrameAt, 1000) - this.frameInterval);
    this.lastFrameAt = now;
    return this.#slice(Math.min(SLOW_BUDGET_MS, SLOW_SHARE * this.frameInterval));
  }

  /** Starts the hidden-page loop if the page is hidden (call on visibilitychange and at start). */
  visibilityChanged() {
    if (!this.isHidden() || this.hiddenLoop) return;
    this.hiddenLoop = true;
    this.#hiddenStep();
  }

  #hiddenStep() {
    if (!this.isHidden()) {
      this.hiddenLoop = false;
    this.lastFrameAt = null;
    this.frameInterval = 16; // smoothed time between animation frames, ms // animation frames take over
      return;
    }
    if (this.#slice()) this.yieldTask(() => this.#hiddenStep());
    else this.setTimer(() => this.#hiddenStep(), HIDDEN_POLL_MS);
  }

  /** Applies frames for the budget (at least `floorMs`); returns true when any was applied. */
  #slice(floorMs = 0) {
    const waiting = this.pending();
    if (waiting === 0) return false;
    const start = this.now();
    this.drain(start + Math.max(floorMs, waiting > BACKLOG_FRAMES ? BACKLOG_BUDGET_MS : BUDGET_MS));
    this.longestSliceMs = Math.max(this.longestSliceMs, this.now() - start);
    return true;
  }
}

/** Runs a function in a new task without timer throttling (hidden pages throttle timers to 1 s). */
function messageChannelTask() {
  let channel = null; // made on first use
  const queue = [];
  return (fn) => {
    if (!channel) {
      channel = new MessageChannel();
      channel.port1.onmessage = () => queue.shift()?.();
    }
    queue.push(fn);
    channel.port2.postMessage(null);
  };
}

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { BACKLOG_BUDGET_MS, BUDGET_MS, FramePump, SLOW_BUDGET_MS } from '../src/frame_pump.js';

/** A queue of frames that each take `costMs` to apply, on a fake clock. */
function fakeQueue(frames, costMs) {
  const clock = { t: 0 };
  const queue = { left: frames, deadlines: [] };
  queue.drain = (deadline) => {
    queue.deadlines.push(deadline - clock.t);
    let applied = 0;
    while (queue.left > 0 && (applied === 0 || clock.t < deadline)) {
      clock.t += costMs;
      --queue.left;
      ++applied;
    }
  };
  return { clock, queue };
}

test('FramePump: an animation frame applies frames for its budget only, never all at once', () => {
  const { clock, queue } = fakeQueue(100, 1);
  const pump = new FramePump({ drain: queue.drain, pending: () => queue.left, isHidden: () => false, now: () => clock.t });
  assert.equal(pump.onAnimationFrame(), true);
  assert.deepEqual(queue.deadlines, [BACKLOG_BUDGET_MS], 'a backlog gets the larger budget');
  assert.equal(queue.left, 100 - BACKLOG_BUDGET_MS);
  while (queue.left > 0) pump.onAnimationFrame();
  assert.ok(queue.deadlines.every((d) => d <= BACKLOG_BUDGET_MS));
  assert.ok(queue.deadlines.at(-1) === BUDGET_MS, 'a short queue gets the normal budget');
  assert.ok(pump.longestSliceMs <= BACKLOG_BUDGET_MS + 1);
  assert.equal(pump.onAnimationFrame(), false, 'nothing queued: nothing done');
});

test('FramePump: slow animation frames get a larger budget, never above SLOW_BUDGET_MS', () => {
  const { clock, queue } = fakeQueue(100000, 1);
  const pump = new FramePump({ drain: queue.drain, pending: () => queue.left, isHidden: () => false, now: () => clock.t });
  for (let i = 0; i < 20; ++i) {
    clock.t += 500; // drawing takes half a second
    pump.onAnimationFrame();
  }
  assert.equal(queue.deadlines.at(-1), SLOW_BUDGET_MS);
  for (let i = 0; i < 40; ++i) {
    clock.t += 16 - queue.deadlines.at(-1); // fast drawing again
    pump.onAnimationFrame();
  }
  assert.equal(queue.deadlines.at(-1), BACKLOG_BUDGET_MS, 'back to the normal budget');
});

test('FramePump: a hidden page applies frames in slices, yielding between them, then polls', () => {
  const { clock, queue } = fakeQueue(40, 1);
  const tasks = [];
  const timers = [];
  let hidden = true;
  const pump = new FramePump({
    drain: queue.drain,
    pending: () => queue.left,
    isHidden: () => hidden,
    now: () => clock.t,
    yieldTask: (fn) => tasks.push(fn),
    setTimer: (fn, ms) => timers.push({ fn, ms }),
  });
  pump.visibilityChanged();
  pump.visibilityChanged(); // a second event does not start a second loop
  let slices = 1;
  while (tasks.length > 0) {
    assert.equal(tasks.length, 1);
    tasks.shift()();
    ++slices;
  }
  assert.equal(queue.left, 0);
  assert.ok(slices >= 40 / BACKLOG_BUDGET_MS, `${slices} slices`);
  assert.ok(queue.deadlines.every((d) => d <= BACKLOG_BUDGET_MS), 'no slice runs unbounded');
  assert.equal(timers.length, 1, 'an empty queue is polled by a timer');
  queue.left = 3;
  hidden = false;
  timers.shift().fn();
  assert.equal(queue.left, 3, 'a visible page leaves frames to animation frames');
  assert.equal(pump.hiddenLoop, false);
});

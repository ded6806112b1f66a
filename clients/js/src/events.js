// A minimal event emitter, the same in browsers and Node (no DOM, no 'events' module).

export class Emitter {
  #listeners = new Map();

  /** Calls `listener(...args)` on every `emit(event, ...args)`; returns a function that stops it. */
  on(event, listener) {
    if (!this.#listeners.has(event)) this.#listeners.set(event, new Set());
    this.#listeners.get(event).add(listener);
    return () => this.off(event, listener);
  }

  off(event, listener) {
    this.#listeners.get(event)?.delete(listener);
  }

  /** Resolves with the arguments of the next `event` (the first one if it carries several). */
  once(event) {
    return new Promise((resolve) => {
      const stop = this.on(event, (value) => {
        stop();
        resolve(value);
      });
    });
  }

  /** Calls the listeners in order; a listener that throws does not stop the others. */
  emit(event, ...args) {
    const listeners = this.#listeners.get(event);
    if (!listeners) return false;
    for (const listener of [...listeners]) {
      try {
        listener(...args);
      } catch (error) {
        queueMicrotask(() => {
          throw error;
        });
      }
    }
    return listeners.size > 0;
  }
}

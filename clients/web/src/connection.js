// The viewer's connection to the server, as the status line tells it.
//
// Once a connection has been open, the client library (clients/js, README "Reconnection")
// reconnects by itself with growing delays and subscribes again to every session, which keeps its
// id and its mesh: the viewer only shows it ('disconnected', then 'open' again). What is left to
// the viewer is the first connection, which the library reports by rejecting (no server yet): it
// is tried again with the library's delays. The page and the <isomesh-surface> element share this.

/** 'connecting' (the first connection) | 'open' | 'disconnected' (retrying, or closed for good). */
export const CONNECTION_STATES = ['connecting', 'open', 'disconnected'];

export class Connection {
  /**
   * @param {object} o
   * @param {(url: string, options: object) => Promise<IsomeshClient>} o.connect the library's
   * @param {string} o.url
   * @param {object} o.options connect's options (decoder, deferFrames...)
   * @param {number[]} o.delaysMs waits between first-connection attempts, the last repeating
   *   (the library's RECONNECT_DELAYS_MS)
   * @param {(connection: Connection) => void} [o.onChange] the state or detail changed
   */
  constructor({ connect, url, options, delaysMs, onChange = () => {} }) {
    Object.assign(this, { connect, url, options, delaysMs, onChange });
    this.client = null;
    this.state = 'connecting';
    /** Why, for the status line: 'reconnecting', 'server unreachable, retrying'... */
    this.detail = '';
    this.stopped = false;
    this.timer = null;
  }

  /** Resolves with the open client, after as many attempts as it takes; null once stopped. */
  async open() {
    for (let attempt = 0; !this.stopped; ++attempt) {
      try {
        const client = await this.connect(this.url, this.options);
        if (this.stopped) {
          client.close();
          return null;
        }
        this.#follow(client);
        return client;
      } catch (error) {
        if (this.stopped) return null;
        this.#set('disconnected', `server unreachable, retrying: ${error.message}`);
        await this.#wait(this.delaysMs[Math.min(attempt, this.delaysMs.length - 1)]);
      }
    }
    return null;
  }

  /** Ends the connection for good (the element left its page). */
  stop() {
    this.stopped = true;
    clearTimeout(this.timer);
    this.timer = null;
    this.wake?.();
    this.client?.close();
  }

  #follow(client) {
    this.client = client;
    client.on('disconnected', () => this.#set('disconnected', 'reconnecting'));
    client.on('reconnected', () => this.#set('open', ''));
    client.on('close', ({ reason }) => !this.stopped && this.#set('disconnected', reason || 'connection closed'));
    this.#set('open', '');
  }

  #set(state, detail) {
    this.state = state;
    this.detail = detail;
    this.onChange(this);
  }

  #wait(ms) {
    return new Promise((resolve) => {
      this.wake = resolve;
      this.timer = setTimeout(resolve, ms);
    });
  }
}

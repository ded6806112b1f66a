// The isomesh client: one WebSocket connection holding any number of sessions (PROTOCOL.md).
//
// Requests get an integer "id" and a Promise settled by the reply that echoes it (`created`,
// `updated`, `subscribed`, `ack`, `pong`, or `error`, which rejects with an IsomeshError). Binary
// frames are decoded and applied to their session's SessionMesh; a sequence gap or a frame that
// cannot be applied makes the session send `resync`, and the server answers with a keyframe.
//
// Reconnection: when the connection drops (a server restart, a crash, a load balancer moving the
// client) or the server says a session moved (`closed` with reason `moved`), the client opens a
// new connection with growing delays and subscribes again to every session it follows; each gets
// a keyframe and goes on. Requests that were in flight are sent again on the new connection when
// sending twice does no harm (update, pause, resume, resync, subscribe, unsubscribe, close: an
// update names the values it sets, so a second copy changes nothing but the version number);
// `create` and `ping` in flight reject with code 'closed', since a second create would make a
// second session. Requests made while disconnected wait for the new connection.
//
// Routing: the connection's URL carries `route=` (8 hex digits, random unless options.route
// gives one). A load balancer hashes it to pick the server, and the sessions this connection
// creates get it as the first 8 digits of their ids (routeOf), so that every client of a
// session reaches the same server (deploy/README.md).
//
// The WebSocket is injectable: the browser's, or the `ws` package's in Node (both offer the same
// onopen/onmessage/onclose/send API). Nothing here touches the DOM.

import { IsomeshError } from './errors.js';
import { Emitter } from './events.js';
import { decodeFrame, readFrameHeader } from './frame.js';
import { SessionMesh, Outcome } from './mesh.js';
import {
  REPLY_TYPES,
  errorFromReply,
  functionFields,
  PROTOCOL_VERSION,
  PROTOCOL_VERSIONS,
  parseServerMessage,
  requestText,
  sessionState,
} from './messages.js';

const now = () => globalThis.performance.now();

/** Requests that may be sent again after a reconnection without changing the outcome. */
const RESENDABLE = new Set(['update', 'pause', 'resume', 'resync', 'subscribe', 'unsubscribe', 'close']);

/** Delays between reconnection attempts (ms), the last one repeating; each is jittered ±20 %. */
export const RECONNECT_DELAYS_MS = Object.freeze([250, 500, 1000, 2000, 4000]);

function utf8Length(text) {
  let bytes = text.length;
  for (let i = 0; i < text.length; ++i) {
    const c = text.charCodeAt(i);
    if (c >= 0x80) bytes += c >= 0x800 && (c < 0xd800 || c > 0xdfff) ? 2 : 1;
  }
  return bytes;
}

/** The route of a session id: its first 8 hex digits (connect with {route} to reach its server). */
export function routeOf(sessionId) {
  return String(sessionId).slice(0, 8).toLowerCase();
}

function randomRoute() {
  const bytes = new Uint8Array(4);
  globalThis.crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
}

/** `url` with `route=` added to its query. */
function routedUrl(url, route) {
  if (!route) return url;
  return `${url}${url.includes('?') ? '&' : '?'}route=${route}`;
}

/**
 * Opens a connection and resolves once it is open.
 * @param {string} url e.g. 'ws://127.0.0.1:8080/ws'
 * @param {object} options
 * @param {{decode(bytes: Uint8Array): object}} options.decoder a DracoMeshDecoder (see
 *   loadDracoDecoder)
 * @param {Function} [options.WebSocket] a WebSocket constructor; default globalThis.WebSocket
 * @param {number} [options.requestTimeoutMs] reject a request whose reply takes longer (30000)
 * @param {boolean} [options.autoResync] send `resync` on a sequence gap (true)
 * @param {number} [options.initialCapacity] triangles each session's slot table starts with
 * @param {boolean} [options.deferFrames] queue binary frames instead of applying them on
 *   receipt; the application then applies them with drainFrames(deadline), e.g. a few
 *   milliseconds per animation frame, so that rendering stays smooth while refinement streams
 * @param {string|null} [options.route] the connection's route, 8 hex digits (random by default;
 *   routeOf(id) to reach the server of session `id`); null: none
 * @param {boolean} [options.reconnect] reconnect and resubscribe when the connection drops (true)
 * @param {number[]} [options.reconnectDelaysMs] delays between attempts (RECONNECT_DELAYS_MS)
 * @param {number} [options.maxReconnectAttempts] attempts in a row before giving up (Infinity)
 * @param {number} [options.protocolVersion] 2 (default: deltas carry only what the client lacks,
 *   PROTOCOL.md 4.5) or 1
 * @returns {Promise<IsomeshClient>}
 */
export function connect(url, options = {}) {
  const WebSocketImpl = options.WebSocket ?? globalThis.WebSocket;
  if (typeof WebSocketImpl !== 'function') {
    return Promise.reject(new TypeError('no WebSocket here: pass options.WebSocket (in Node, the ws package)'));
  }
  if (!options.decoder || typeof options.decoder.decode !== 'function') {
    return Promise.reject(new TypeError('pass options.decoder: await loadDracoDecoder()'));
  }
  if (options.route != null && !/^[0-9a-fA-F]{8}$/.test(options.route)) {
    return Promise.reject(new TypeError('options.route must be 8 hex digits'));
  }
  if (options.protocolVersion !== undefined && !PROTOCOL_VERSIONS.includes(options.protocolVersion)) {
    return Promise.reject(new TypeError(`options.protocolVersion must be one of ${PROTOCOL_VERSIONS.join(', ')}`));
  }
  const client = new IsomeshClient(url, { ...options, WebSocket: WebSocketImpl });
  return client.opened.then(() => client);
}

export class IsomeshClient extends Emitter {
  /** Use connect(). */
  constructor(url, options) {
    super();
    this.url = url;
    this.decoder = options.decoder;
    this.options = {
      requestTimeoutMs: 30000,
      autoResync: true,
      reconnect: true,
      reconnectDelaysMs: RECONNECT_DELAYS_MS,
      maxReconnectAttempts: Infinity,
      protocolVersion: PROTOCOL_VERSION,
      ...options,
    };
    /** The connection's route (8 hex digits), or null. */
    this.route = options.route === undefined ? randomRoute() : options.route && options.route.toLowerCase();
    /** Session id (hex) -> Session, for every session this connection receives. */
    this.sessions = new Map();
    this.bytesReceived = 0;
    this.framesReceived = 0;
    this.messagesReceived = 0;
    /** True once the client is closed for good (close(), or reconnection given up). */
    this.closed = false;
    /** True while a WebSocket is open. */
    this.connected = false;
    /** Completed reconnections. */
    this.reconnects = 0;
    this.pending = new Map(); // id -> {resolve, reject, timer, onReply, type, text, sent}
    this.nextRequestId = 1;
    this.frameQueue = []; // with deferFrames: frames not applied yet, from frameQueueHead on
    this.frameQueueHead = 0;
    this.attempts = 0; // failed reconnection attempts in a row
    this.reconnectTimer = null;
    this.closing = false;
    this.opened = new Promise((resolve, reject) => {
      this.#open(resolve, reject);
    });
  }

  /** The WebSocket of the current connection (replaced on each reconnection). */
  get socket() {
    return this.currentSocket;
  }

  /**
   * Creates a session: {expression | vm, parameters, box, constraints}. Resolves with the Session
   * once `created` arrives; its keyframe and deltas follow as events.
   */
  async create(options) {
    const fields = functionFields(options);
    const startedAt = now();
    return this.request('create', fields, (reply) => this.#adopt(reply, startedAt));
  }

  /** Subscribes to an existing session (by its hex id); a keyframe follows the reply. */
  async subscribe(sessionId) {
    const known = this.sessions.get(sessionId);
    if (known) return known;
    const startedAt = now();
    return this.request('subscribe', { session: sessionId }, (reply) => this.#adopt(reply, startedAt));
  }

  /** Round trip: resolves with {rttMs, serverTimeUs}. */
  async ping() {
    const startedAt = now();
    const reply = await this.request('ping');
    return { rttMs: now() - startedAt, serverTimeUs: reply.time_us };
  }

  /**
   * Sends a request and resolves with its reply (rejects with an IsomeshError on an `error`
   * reply, a timeout or a closed connection). The building block of every method here.
   * `onReply(reply)`, if given, runs as soon as the reply is read, before any later message or
   * frame is handled (a session must exist before its keyframe arrives), and its result is what
   * the promise resolves with. While reconnecting, the request waits for the new connection.
   */
  request(type, fields = {}, onReply = (reply) => reply) {
    if (this.closed) return Promise.reject(new IsomeshError('closed', 'the connection is closed'));
    const id = this.nextRequestId++;
    const text = requestText(type, id, fields, this.options.protocolVersion);
    return new Promise((resolve, reject) => {
      const timer = setTimeout(() => {
        this.pending.delete(id);
        reject(new IsomeshError('timeout', `no reply to ${type} within ${this.options.requestTimeoutMs} ms`));
      }, this.options.requestTimeoutMs);
      const entry = { resolve, reject, timer, onReply, type, text, sent: false };
      this.pending.set(id, entry);
      if (this.connected) this.#transmit(entry);
    });
  }

  /** Sends a message that expects no reply (e.g. resync); dropped while disconnected. */
  send(type, fields = {}) {
    if (this.connected) this.currentSocket.send(requestText(type, undefined, fields, this.options.protocolVersion));
  }

  /**
   * With deferFrames: applies the queued frames in order until performance.now() passes
   * `deadline` (at least one frame per call). Returns how many frames remain queued.
   */
  drainFrames(deadline = Infinity) {
    const queue = this.frameQueue;
    let applied = 0;
    while (this.frameQueueHead < queue.length && (applied === 0 || now() < deadline)) {
      const bytes = queue[this.frameQueueHead];
      queue[this.frameQueueHead++] = null;
      this.#applyFrame(bytes);
      ++applied;
    }
    if (this.frameQueueHead === queue.length) {
      this.frameQueue = [];
      this.frameQueueHead = 0;
    }
    return this.pendingFrames;
  }

  /** Frames received but not applied yet (always 0 without deferFrames). */
  get pendingFrames() {
    return this.frameQueue.length - this.frameQueueHead;
  }

  /** Closes the connection for good (sessions it created expire on the server unless others subscribe). */
  close() {
    this.closing = true;
    clearTimeout(this.reconnectTimer);
    if (this.connected) {
      this.currentSocket.close(1000, 'client closed');
    } else {
      this.#final({ code: 1000, reason: 'client closed' });
    }
  }

  // ---- connection and reconnection ---------------------------------------------------------------

  /**
   * Opens a WebSocket; `opened` or `failed` settles the attempt, once: a socket that cannot
   * connect fires `error` and then `close` (browsers and `ws` alike), and each call of `failed`
   * would schedule its own next attempt, doubling the attempts in flight with every failure.
   */
  #open(opened, failed) {
    const socket = new this.options.WebSocket(routedUrl(this.url, this.route));
    this.currentSocket = socket;
    let open = false;
    let settled = false;
    const fail = (error) => {
      if (settled) return;
      settled = true;
      failed(error);
    };
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => {
      if (settled) return;
      settled = true;
      open = true;
      this.connected = true;
      opened();
    };
    socket.onerror = () => {
      if (!open) fail(new IsomeshError('unavailable', 'WebSocket connection failed'));
    };
    socket.onmessage = (event) => {
      if (socket === this.currentSocket) this.#receive(event.data);
    };
    socket.onclose = (event) => {
      if (socket !== this.currentSocket) return;
      if (!open) {
        fail(new IsomeshError('unavailable', `WebSocket connection failed (${event.code})`));
        return;
      }
      this.#lost(event);
    };
  }

  /** The open connection ended: for good, or to be reopened. */
  #lost(event) {
    this.connected = false;
    if (this.closing || !this.options.reconnect) {
      this.#final(event);
      return;
    }
    for (const [id, entry] of this.pending) {
      if (!entry.sent) continue;
      if (RESENDABLE.has(entry.type)) {
        entry.sent = false; // sent again on the next connection
      } else {
        this.pending.delete(id);
        clearTimeout(entry.timer);
        entry.reject(new IsomeshError('closed', `connection lost before the reply to ${entry.type}`));
      }
    }
    // Frames of the lost connection not applied yet are dropped: every session subscribes again
    // and its keyframe comes first.
    this.frameQueue = [];
    this.frameQueueHead = 0;
    for (const session of this.sessions.values()) session._connectionLost();
    this.emit('disconnected', { code: event.code, reason: event.reason });
    this.#scheduleReconnect();
  }

  #scheduleReconnect() {
    if (this.attempts >= this.options.maxReconnectAttempts) {
      this.#final({ code: 1006, reason: `gave up after ${this.attempts} reconnection attempts` });
      return;
    }
    const delays = this.options.reconnectDelaysMs;
    const delay = delays[Math.min(this.attempts, delays.length - 1)] * (0.8 + 0.4 * Math.random());
    ++this.attempts;
    this.reconnectTimer = setTimeout(() => {
      this.#open(
        () => this.#resume(),
        () => {
          if (!this.closing) this.#scheduleReconnect();
        },
      );
    }, delay);
  }

  /** A new connection is open: subscribe again, then send what waited. */
  #resume() {
    const attempts = this.attempts;
    this.attempts = 0;
    ++this.reconnects;
    for (const session of this.sessions.values()) {
      if (!session.resubscribing) this.#resubscribe(session); // else its request is sent below
    }
    for (const entry of this.pending.values()) {
      if (!entry.sent) this.#transmit(entry);
    }
    this.emit('reconnected', { attempts, sessions: this.sessions.size });
  }

  #resubscribe(session) {
    const startedAt = now();
    session.resubscribing = true;
    this.request('subscribe', { session: session.id }, (reply) => {
      session.resubscribing = false;
      session._setState(sessionState(reply), startedAt);
      session.emit('resubscribed', session.state);
      return session;
    }).catch((error) => {
      session.resubscribing = false;
      if (this.closed || this.sessions.get(session.id) !== session) return;
      if (error.code === 'store_unavailable' || error.code === 'timeout' || error.code === 'closed') {
        // The server cannot load it now: try again (a lost connection resubscribes anyway).
        if (error.code !== 'closed') setTimeout(() => this.connected && this.#resubscribe(session), 1000);
        return;
      }
      this.sessions.delete(session.id);
      session._onMessage({ type: 'closed', session: session.id, reason: 'lost', error });
    });
  }

  /** The server says a session moved: reconnect (the load balancer picks its new server). */
  #moved() {
    if (!this.connected || this.closing || !this.options.reconnect) return;
    this.currentSocket.close(4000, 'session moved');
  }

  #transmit(entry) {
    entry.sent = true;
    this.currentSocket.send(entry.text);
  }

  #final(event) {
    this.closed = true;
    this.connected = false;
    const error = new IsomeshError('closed', `connection closed (${event.code}${event.reason ? `: ${event.reason}` : ''})`);
    for (const { reject, timer } of this.pending.values()) {
      clearTimeout(timer);
      reject(error);
    }
    this.pending.clear();
    this.emit('close', { code: event.code, reason: event.reason });
  }

  // ---- messages and frames -----------------------------------------------------------------------

  #adopt(reply, startedAt) {
    let session = this.sessions.get(reply.session);
    if (!session) {
      session = new Session(this, reply.session, { initialCapacity: this.options.initialCapacity });
      this.sessions.set(reply.session, session);
    }
    session._setState(sessionState(reply), startedAt);
    // The read-only id to share with viewers (holders of the control id only), and what the id
    // this connection holds allows: 'control' or 'view' (PROTOCOL.md 3.2).
    session.view = reply.view;
    session.access = reply.access ?? 'control';
    return session;
  }

  #receive(data) {
    if (typeof data === 'string') {
      this.#receiveText(data);
    } else {
      const bytes = data instanceof ArrayBuffer ? new Uint8Array(data) : new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
      this.bytesReceived += bytes.length;
      ++this.framesReceived;
      if (this.options.deferFrames) this.frameQueue.push(bytes);
      else this.#applyFrame(bytes);
    }
  }

  #receiveText(text) {
    this.bytesReceived += utf8Length(text);
    ++this.messagesReceived;
    let message;
    try {
      message = parseServerMessage(text);
    } catch (error) {
      this.emit('error', error);
      return;
    }
    this.emit('message', message);
    if (REPLY_TYPES.has(message.type) && message.id !== undefined && this.pending.has(message.id)) {
      this.#settle(message);
      return;
    }
    const session = message.session !== undefined ? this.sessions.get(message.session) : undefined;
    if (session && message.type === 'closed' && message.reason === 'moved' && this.options.reconnect) {
      session.emit('moved', message);
      this.#moved();
    } else if (session) {
      session._onMessage(message);
      if (message.type === 'closed') this.sessions.delete(message.session);
    } else if (message.type === 'error') {
      this.emit('error', errorFromReply(message));
    }
  }

  /** A reply to pending request `message.id`. */
  #settle(message) {
    const entry = this.pending.get(message.id);
    if (message.type === 'error' && message.code === 'wrong_route' && RESENDABLE.has(entry.type) &&
        entry.type !== 'subscribe' && this.options.reconnect) {
      entry.sent = false; // the session moved to another server: sent again after reconnecting
      this.#moved();
      return;
    }
    this.pending.delete(message.id);
    clearTimeout(entry.timer);
    if (message.type === 'error') {
      entry.reject(errorFromReply(message));
      return;
    }
    try {
      entry.resolve(entry.onReply(message));
    } catch (error) {
      entry.reject(error);
    }
  }

  #applyFrame(bytes) {
    let frame;
    try {
      frame = decodeFrame(bytes, this.decoder);
    } catch (error) {
      this.#badFrame(bytes, error);
      return;
    }
    this.sessions.get(frame.header.session)?._onFrame(frame, bytes.length);
  }

  /** A frame that does not decode: the session it names, if any, has lost a step. */
  #badFrame(bytes, error) {
    let session;
    try {
      session = this.sessions.get(readFrameHeader(bytes).session);
    } catch {
      session = undefined;
    }
    if (session) session._onBadFrame(error);
    else this.emit('error', error);
  }
}

/**
 * One session as this connection sees it: its settings, its mesh (ready to render), statistics,
 * and events:
 *   'state'      (state)             after created/updated/subscribed: version, parameters, box...
 *   'keyframe'   (frame)             a keyframe was applied (the whole mesh was replaced)
 *   'delta'      (frame)             a delta was applied
 *   'firstMesh'  ({version, ms})     the first frame of a function version, ms after its request
 *   'progress'   (message)           refinement statistics
 *   'converged'  (message)           the constraints are met for message.version
 *   'resync'     ({reason})          a gap or a bad frame: a keyframe was asked for
 *   'error'      (IsomeshError)      an error about this session that answers no request
 *   'disconnected' ()                the connection dropped; the client reconnects
 *   'moved'      (message)           the server says the session moved; the client reconnects
 *   'resubscribed' (state)           subscribed again after a reconnection (a keyframe follows)
 *   'closed'     (message)           the session ended (message.reason; 'lost' when it could not
 *                                    be subscribed again after a reconnection)
 */
export class Session extends Emitter {
  constructor(client, id, meshOptions) {
    super();
    this.client = client;
    this.id = id;
    this.mesh = new SessionMesh(meshOptions);
    this.state = null;
    this.lastProgress = null;
    this.lastConverged = null;
    this.closed = false;
    this.stats = { bytes: 0, frames: 0, keyframes: 0, deltas: 0, resyncs: 0, firstMeshMs: null, lastFrameAt: null };
    this.pendingUpdates = 0;
    this.resyncPending = false;
    this.resubscribing = false; // a subscribe after a reconnection awaits its reply
    this.versionStart = null; // {startedAt, version} of the last request awaiting its first mesh
  }

  /** True when the mesh on hand is final for the latest function version. */
  get converged() {
    return (
      this.pendingUpdates === 0 &&
      this.state !== null &&
      this.lastConverged !== null &&
      this.lastConverged.version === this.state.version &&
      this.mesh.synchronized &&
      this.mesh.sequence >= this.lastConverged.sequence
    );
  }

  /**
   * A new function version: any of {expression | vm, parameters (merged), box, constraints (field
   * by field)}. Resolves with the new state; rejects with IsomeshError (e.g. code
   * 'bad_expression' with a column) and then the session keeps its previous version.
   */
  async update(options) {
    const fields = functionFields(options);
    const startedAt = now();
    ++this.pendingUpdates;
    let answered = false;
    const settle = () => {
      if (!answered) --this.pendingUpdates;
      answered = true;
    };
    try {
      return await this.client.request('update', { session: this.id, ...fields }, (reply) => {
        settle(); // before the frames of the new version are handled
        this._setState(sessionState(reply), startedAt);
        return this.state;
      });
    } finally {
      settle();
    }
  }

  pause() {
    return this.#ack('pause');
  }

  resume() {
    return this.#ack('resume');
  }

  /** Stops receiving this session's frames on this connection (the session lives on). */
  async unsubscribe() {
    await this.#ack('unsubscribe');
    this.client.sessions.delete(this.id);
  }

  /** Ends the session for every subscriber. */
  async close() {
    await this.#ack('close');
    this.closed = true;
    this.client.sessions.delete(this.id);
  }

  /** Asks for a fresh keyframe (done automatically on a sequence gap). */
  resync() {
    this.resyncPending = true;
    ++this.stats.resyncs;
    return this.#ack('resync');
  }

  #ack(type) {
    return this.client.request(type, { session: this.id });
  }

  _setState(state, startedAt) {
    this.state = state;
    if (this.mesh.functionVersion >= state.version && this.stats.lastFrameAt !== null) {
      this.#firstMesh(state.version, this.stats.lastFrameAt - startedAt);
    } else {
      this.versionStart = { startedAt, version: state.version };
    }
    this.emit('state', state);
  }

  _onFrame(frame, byteLength) {
    const at = now();
    const h = frame.header;
    this.stats.bytes += byteLength;
    ++this.stats.frames;
    const outcome = this.mesh.apply(frame);
    if (outcome === Outcome.applied) {
      this.stats.lastFrameAt = at;
      if (h.kind === 'keyframe') {
        ++this.stats.keyframes;
        this.resyncPending = false;
      } else {
        ++this.stats.deltas;
      }
      this.emit(h.kind, frame);
      const start = this.versionStart;
      if (start && h.functionVersion >= start.version) this.#firstMesh(h.functionVersion, at - start.startedAt);
    } else if (outcome === Outcome.gap || outcome === Outcome.inconsistent) {
      this.#lostStep(outcome);
    }
  }

  /** The connection dropped: the mesh stays on hand, not known to be final until resubscribed. */
  _connectionLost() {
    // The next frame to apply is the keyframe of the new subscription: a session rebuilt after a
    // restart numbers its frames from 0 again (PROTOCOL.md 3.6), so its `converged` must not be
    // measured against the sequence of the mesh on hand (which stays shown meanwhile).
    this.mesh.synchronized = false;
    this.lastConverged = null;
    this.lastProgress = null;
    this.resyncPending = false;
    this.stats.lastFrameAt = null; // the first mesh after resubscribing is timed from its request
    this.emit('disconnected');
  }

  _onBadFrame(error) {
    this.mesh.synchronized = false;
    this.emit('error', error);
    this.#lostStep('bad_frame');
  }

  _onMessage(message) {
    switch (message.type) {
      case 'progress':
        this.lastProgress = message;
        this.emit('progress', message);
        break;
      case 'converged':
        this.lastConverged = message;
        this.emit('converged', message);
        break;
      case 'updated': // without an id: a version another controller made (PROTOCOL.md 2.2)
        this.state = sessionState(message);
        this.emit('state', this.state);
        break;
      case 'closed':
        this.closed = true;
        this.emit('closed', message);
        break;
      case 'error':
        this.emit('error', errorFromReply(message));
        break;
      default:
        break;
    }
  }

  #firstMesh(version, ms) {
    this.versionStart = null;
    this.stats.firstMeshMs = ms;
    this.emit('firstMesh', { version, ms });
  }

  #lostStep(reason) {
    if (!this.client.options.autoResync || this.resyncPending || this.closed) return;
    this.emit('resync', { reason });
    this.resync().catch((error) => {
      this.resyncPending = false; // the next gap may try again
      this.emit('error', error);
    });
  }
}

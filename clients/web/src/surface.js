// One surface: an equation, its session on the server, and the user's edits turned into `update`
// requests. The page has one per row of the object list; the <isomesh-surface> element has one.
//
// Edits are coalesced: at most one update is in flight, and edits made meanwhile (a slider being
// dragged) are merged into the next one. That one is sent once the server has answered the
// previous update *and* its mesh has appeared (or after NEXT_UPDATE_WAIT_MS, for a function
// whose mesh takes long): each step of a drag is then drawn instead of being superseded on the
// server before its first mesh, so the surface follows the slider at the pace of the server.
//
// Values shared by every surface (parameters, box, constraints) are not kept here: `shared()`
// returns them when a session is created.
//
// The session outlives the connection: when it drops, the client library reconnects and
// subscribes again (same session id, same mesh; clients/js README, "Reconnection") and edits made
// meanwhile wait for it. A new session is made only when the server says the old one is gone:
// `closed` with reason `lost` (it could not be subscribed again: a server without a store
// restarted) or `shutdown`, or an `unknown_session` error answering a request. A session the
// server ended on purpose (`expired`: no request for its idle time; `closed` by another client)
// is not made again at once: the surface says so ('ended') and the next edit or Enter makes it.

import { missingParameters, parameterNames, valuesFor } from './parameters.js';

export const NEXT_UPDATE_WAIT_MS = 250;
/** Wait before sending again a request the server could not take (store down, timed out). */
export const RETRY_MS = 2000;
/** Error codes that say "not now" rather than "not this": the request is made again. */
const RETRIED = new Set(['timeout', 'closed', 'unavailable', 'store_unavailable']);
/** Reasons of `closed` that end the session but not the surface: a new session is made. */
const RECREATED = new Set(['lost', 'shutdown']);

/** What a row's progress line says, from the surface's state. */
export const SURFACE_STATES = ['empty', 'error', 'ended', 'connecting', 'disconnected', 'meshing', 'resolving', 'refining', 'converged', 'paused'];

export class Surface {
  /**
   * @param {object} options
   * @param {string} [options.expression] the equation (already through prepareEquation)
   * @param {() => {parameters, box, constraints}} options.shared the scene's common values
   * @param {(surface: Surface, what: string) => void} options.onChange 'session' (a new session:
   *   its mesh is session.mesh), 'state' (the server's reply), 'mesh' (frames applied), 'error',
   *   'status'
   */
  constructor({ expression = '', shared, onChange = () => {} }) {
    this.expression = expression;
    this.shared = shared;
    this.onChange = onChange;
    this.client = null;
    this.session = null;
    this.creating = false;
    this.pending = null; // fields of the next update
    this.inFlight = false;
    this.waitingFor = null; // {version, timer}: the update answered, its mesh not shown yet
    this.error = null; // {code, message, column, text, transient} of the last rejected request
    this.retryTimer = null; // a request the server could not take is made again when it fires
    this.unfollow = null; // stops listening to the client
    this.errorMax = null; // of the current function version only
    this.paused = false;
    /** The `closed` reason of a session the server ended on purpose, until a new one is made. */
    this.ended = null;
    /** Function versions whose mesh has been shown: how many times the surface moved. */
    this.versionsShown = 0;
    this.lastShownVersion = 0;
    /** The last 200 session events, for diagnostics. */
    this.journal = [];
  }

  /**
   * Uses `client` (an open IsomeshClient, reconnecting by itself) from now on: creates the
   * session if there is an equation.
   */
  attach(client) {
    this.client = client;
    this.unfollow = client.on('reconnected', () => this.#retry());
    if (this.expression !== '') this.#create();
  }

  /** The names the slider panel shows: the server's list once known, else the equation's. */
  get parameterNames() {
    return this.session?.state ? Object.keys(this.session.state.parameters) : parameterNames(this.expression);
  }

  get triangles() {
    return this.session?.mesh.triangleCount ?? 0;
  }

  // ---- edits -----------------------------------------------------------------------------------

  setExpression(expression) {
    this.expression = expression;
    const parameters = valuesFor(parameterNames(expression), this.shared().parameters);
    this.#change({ expression, parameters });
  }

  /** New values of shared parameters: sent if this surface uses any of them. */
  setParameters(values) {
    const used = this.parameterNames;
    const mine = Object.fromEntries(Object.entries(values).filter(([name]) => used.includes(name)));
    if (Object.keys(mine).length > 0) this.#change({ parameters: mine });
  }

  setBox(box) {
    this.#change({ box });
  }

  setConstraints(constraints) {
    this.#change({ constraints });
  }

  async setPaused(paused) {
    this.paused = paused;
    if (!this.session) return;
    const session = this.session;
    await (paused ? session.pause() : session.resume()).catch((error) => {
      if (error.code === 'unknown_session') this.#gone(session);
      else this.#failed(error, {});
    });
    this.onChange(this, 'status');
  }

  /** Ends the session on the server (the row was deleted). */
  async close() {
    const session = this.session;
    this.session = null;
    this.expression = '';
    this.#stopWaiting();
    clearTimeout(this.retryTimer);
    this.unfollow?.();
    if (session && !session.closed) await session.close().catch(() => {});
  }

  // ---- state -----------------------------------------------------------------------------------

  /** One of SURFACE_STATES. */
  get status() {
    const s = this.session;
    if (this.expression === '' && !s) return 'empty';
    if (!this.client) return 'connecting';
    if (!this.client.connected) return 'disconnected'; // the mesh on hand stays shown
    if (!s && !this.creating) {
      if (this.error && !this.error.transient) return 'error';
      if (this.ended) return 'ended';
    }
    if (!s) return 'meshing';
    if (this.paused) return 'paused';
    if (this.finished) return 'converged'; // a version may converge with no frame
    if (this.#busy || !s.mesh.synchronized || s.mesh.functionVersion < (s.state?.version ?? 0)) return 'meshing';
    return this.resolving ? 'resolving' : 'refining';
  }

  /** The server's `converged` message when the mesh on hand is final for the latest version, else null. */
  get finished() {
    const s = this.session;
    return s && !this.#busy && s.converged ? s.lastConverged : null;
  }

  /** True while the server is still finding the current version's shape (a keyframe may replace the mesh). */
  get resolving() {
    const p = this.session?.lastProgress;
    return Boolean(p && p.version === this.session.state?.version && p.resolving);
  }

  get #busy() {
    return Boolean(this.pending || this.inFlight);
  }

  snapshot() {
    const s = this.session;
    return {
      expression: this.expression,
      status: this.status,
      session: s?.id ?? null,
      version: s?.state?.version ?? null,
      sequence: s?.mesh.sequence ?? null,
      triangles: this.triangles,
      errorMax: this.errorMax,
      firstMeshMs: s?.stats.firstMeshMs ?? null,
      versionsShown: this.versionsShown,
      resolving: this.resolving,
      outcome: outcomeOf(this.finished),
      ended: this.ended,
      parameters: { ...(s?.state?.parameters ?? {}) },
      box: s?.state?.box ?? null,
      constraints: s?.state?.constraints ?? null,
      error: this.error,
    };
  }

  // ---- session ---------------------------------------------------------------------------------

  async #create() {
    if (this.creating || this.session || !this.client) return;
    const client = this.client;
    const expression = this.expression;
    const { parameters, box, constraints } = this.shared();
    this.creating = true;
    this.onChange(this, 'status');
    let names = parameterNames(expression);
    let session = null;
    for (let attempt = 0; ; ++attempt) {
      try {
        session = await client.create({ expression, parameters: valuesFor(names, parameters), box, constraints });
        break;
      } catch (error) {
        const missing = missingParameters(error).filter((name) => !names.includes(name));
        if (attempt === 0 && missing.length > 0) {
          names = [...names, ...missing];
          continue;
        }
        this.creating = false;
        if (this.expression === '') return; // deleted meanwhile
        if (RETRIED.has(error.code)) this.#retryLater(error);
        else this.#failed(error, { expression });
        return;
      }
    }
    this.creating = false;
    if (this.expression === '') {
      session.close().catch(() => {}); // deleted meanwhile
      return;
    }
    this.session = session;
    this.ended = null;
    this.error = null;
    this.errorMax = null;
    this.lastShownVersion = 0; // versions count from 1 in every session
    this.#watch(session);
    if (this.paused) session.pause().catch(() => {});
    this.onChange(this, 'session');
    this.onChange(this, 'state');
    this.#catchUp(expression);
    this.#pump();
  }

  /** Sends what changed while the session was being created (an edit, a slider moved). */
  #catchUp(expression) {
    const now = this.shared();
    const state = this.session.state;
    const fields = {};
    if (this.expression !== expression) fields.expression = this.expression;
    const parameters = Object.fromEntries(
      Object.entries(state.parameters).filter(([name, value]) => name in now.parameters && now.parameters[name] !== value).map(([name]) => [name, now.parameters[name]]),
    );
    if (Object.keys(parameters).length > 0) fields.parameters = parameters;
    if (now.box.some((v, i) => v !== state.box[i])) fields.box = now.box;
    const constraints = Object.fromEntries(Object.entries(now.constraints).filter(([key, value]) => value !== undefined && value !== state.constraints?.[key]));
    if (Object.keys(constraints).length > 0) fields.constraints = constraints;
    if (Object.keys(fields).length > 0) this.#change(fields);
  }

  #note(entry) {
    this.journal.push(entry);
    if (this.journal.length > 200) this.journal.shift();
  }

  #watch(session) {
    const current = () => this.session === session;
    const noteFrame = ({ header: h, removed, triangleIds }) =>
      this.#note(`${h.kind} s${h.sequence} v${h.functionVersion} -${removed.length} +${triangleIds.length}${h.converged ? ' converged' : ''}`);
    let version = session.state.version;
    session.on('state', (state) => {
      this.#note(`state v${state.version} ${JSON.stringify(state.parameters)}`);
      if (state.version !== version) this.errorMax = null; // never the previous version's error
      version = state.version;
    });
    const meshChanged = (frame) => {
      noteFrame(frame);
      if (!current()) return;
      const shown = frame.header.functionVersion;
      if (shown > this.lastShownVersion) {
        this.lastShownVersion = shown;
        ++this.versionsShown;
      }
      if (this.waitingFor && shown >= this.waitingFor.version) this.#meshArrived();
      this.onChange(this, 'mesh');
    };
    session.on('keyframe', meshChanged);
    session.on('delta', meshChanged);
    session.on('resync', ({ reason }) => this.#note(`resync (${reason})`));
    session.on('firstMesh', () => current() && this.onChange(this, 'status'));
    session.on('progress', (m) => {
      this.#note(`progress v${m.version} ${m.triangles}${m.resolving ? ' resolving' : ''}`);
      if (!current()) return;
      if (m.version === session.state?.version) this.errorMax = m.error_max;
      this.onChange(this, 'status');
    });
    session.on('converged', (m) => {
      this.#note(`converged v${m.version} s${m.sequence}`);
      if (!current()) return;
      if (m.version === session.state?.version) this.errorMax = m.error_max;
      if (this.waitingFor && m.version >= this.waitingFor.version) this.#meshArrived();
      this.onChange(this, 'status');
    });
    session.on('error', (error) => {
      if (!current()) return;
      this.error = { code: error.code, message: error.message, column: error.column ?? null, text: this.expression };
      this.onChange(this, 'error');
    });
    session.on('disconnected', () => current() && this.onChange(this, 'status'));
    session.on('resubscribed', (state) => {
      this.#note(`resubscribed v${state.version}`);
      if (!current()) return;
      if (this.paused) session.pause().catch(() => {}); // a rebuilt session is not paused
      this.onChange(this, 'status');
    });
    session.on('closed', (m) => {
      this.#note(`closed (${m.reason})`);
      if (!current()) return;
      if (RECREATED.has(m.reason)) {
        this.#gone(session);
        return;
      }
      if (m.reason !== 'error') this.ended = m.reason; // after `error`, the error says why
      this.#forget();
    });
  }

  /** The session ended; the surface keeps its equation (a later edit makes a new session). */
  #forget() {
    this.session = null;
    this.pending = null;
    this.#stopWaiting();
    this.onChange(this, 'session');
  }

  /** The server no longer has the session: a new one, with the surface's current definition. */
  #gone(session) {
    if (this.session !== session) return;
    this.#forget();
    this.#create();
  }

  /** After a reconnection or a wait: makes again what the server could not take. */
  #retry() {
    clearTimeout(this.retryTimer);
    this.retryTimer = null;
    if (!this.client?.connected || this.expression === '') return;
    if (this.session) this.#pump();
    else this.#create();
  }

  /** The request failed for now (`error.code` in RETRIED): again after RETRY_MS or a reconnection. */
  #retryLater(error) {
    const said = error.code === 'unavailable' || error.code === 'store_unavailable'; // the server's words
    if (said) this.error = { code: error.code, message: error.message, column: null, text: this.expression, transient: true };
    clearTimeout(this.retryTimer);
    this.retryTimer = setTimeout(() => this.#retry(), RETRY_MS);
    this.onChange(this, said ? 'error' : 'status');
  }

  #change(fields) {
    if (!this.session) {
      // No session yet (none created, or its creation failed on a bad equation): create one with
      // everything, once there is an equation.
      if (fields.expression !== undefined) this.error = null;
      if (this.client && !this.client.closed && this.expression !== '') this.#create();
      this.onChange(this, 'status');
      return;
    }
    this.pending = mergeFields(this.pending, fields);
    this.onChange(this, 'status');
    this.#pump();
  }

  async #pump() {
    if (this.inFlight || this.waitingFor || this.retryTimer || !this.session || !this.pending) return;
    const session = this.session;
    const fields = this.pending;
    this.pending = null;
    this.inFlight = true;
    try {
      const state = await session.update(fields);
      if (fields.expression !== undefined || this.error?.transient) this.error = null;
      if (this.session === session) this.#waitForMesh(state.version);
      this.onChange(this, 'state');
    } catch (error) {
      const missing = missingParameters(error).filter((name) => !(name in (fields.parameters ?? {})));
      if (this.session !== session) {
        // The session was replaced meanwhile; the new one was made with everything.
      } else if (error.code === 'unknown_session') {
        this.#gone(session);
      } else if (RETRIED.has(error.code)) {
        this.pending = mergeFields(fields, this.pending ?? {});
        this.#retryLater(error);
      } else if (fields.expression !== undefined && missing.length > 0) {
        const parameters = { ...fields.parameters, ...valuesFor(missing, this.shared().parameters) };
        this.pending = mergeFields({ ...fields, parameters }, this.pending ?? {});
      } else {
        this.#failed(error, fields);
      }
    } finally {
      this.inFlight = false;
    }
    this.#pump();
    this.onChange(this, 'status');
  }

  /** Holds the next update until the mesh of `version` shows (or a short while passes). */
  #waitForMesh(version) {
    if (this.session.mesh.functionVersion >= version) return;
    const timer = setTimeout(() => this.#meshArrived(), NEXT_UPDATE_WAIT_MS);
    this.waitingFor = { version, timer };
  }

  #meshArrived() {
    this.#stopWaiting();
    this.#pump();
  }

  #stopWaiting() {
    if (this.waitingFor) clearTimeout(this.waitingFor.timer);
    this.waitingFor = null;
  }

  #failed(error, fields) {
    this.error = {
      code: error.code ?? 'internal',
      message: error.message,
      column: error.column ?? null,
      text: fields.expression ?? this.expression,
    };
    this.onChange(this, 'error');
  }
}

/** What a row shows of a `converged` message: null while the mesh is not final. */
function outcomeOf(converged) {
  if (!converged) return null;
  return {
    outcome: converged.outcome ?? 'surface',
    certified: converged.certified ?? null,
    unresolvedCells: converged.unresolved_cells ?? null,
    budgetUnreachable: Boolean(converged.budget_unreachable),
    triangles: converged.triangles,
  };
}

/** Later fields win; parameters and constraints merge name by name. */
export function mergeFields(earlier, later) {
  if (!earlier) return { ...later };
  const merged = { ...earlier, ...later };
  if (earlier.parameters || later.parameters) merged.parameters = { ...earlier.parameters, ...later.parameters };
  if (earlier.constraints || later.constraints) merged.constraints = { ...earlier.constraints, ...later.constraints };
  return merged;
}

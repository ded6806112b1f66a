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

import { missingParameters, parameterNames, valuesFor } from './parameters.js';

export const NEXT_UPDATE_WAIT_MS = 250;
/** Delays before reconnecting after a lost connection: the 1st, 2nd... attempt (then the last). */
export const RECONNECT_MS = [500, 1000, 2000, 5000, 10000];

/** What a row's progress line says, from the surface's state. */
export const SURFACE_STATES = ['empty', 'error', 'connecting', 'meshing', 'refining', 'converged', 'paused'];

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
    this.error = null; // {code, message, column, text} of the last rejected request
    this.errorMax = null; // of the current function version only
    this.paused = false;
    /** Function versions whose mesh has been shown: how many times the surface moved. */
    this.versionsShown = 0;
    this.lastShownVersion = 0;
    /** The last 200 session events, for diagnostics. */
    this.journal = [];
  }

  /** Uses `client` (an open IsomeshClient) from now on: creates the session if there is an equation. */
  attach(client) {
    this.client = client;
    if (this.expression !== '') this.#create();
  }

  /** The connection is gone: forget the session (a new one is made on the next attach). */
  detach() {
    this.client = null;
    this.session = null;
    this.creating = false;
    this.pending = null;
    this.inFlight = false;
    this.#stopWaiting();
    this.onChange(this, 'session');
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
    await (paused ? this.session.pause() : this.session.resume()).catch((e) => this.#failed(e, {}));
    this.onChange(this, 'status');
  }

  /** Ends the session on the server (the row was deleted). */
  async close() {
    const session = this.session;
    this.session = null;
    this.expression = '';
    this.#stopWaiting();
    if (session && !session.closed) await session.close().catch(() => {});
  }

  // ---- state -----------------------------------------------------------------------------------

  /** 'empty' | 'error' | 'connecting' | 'meshing' | 'refining' | 'converged' | 'paused' */
  get status() {
    const s = this.session;
    if (!s) {
      if (this.expression === '') return 'empty';
      if (this.error && !this.creating) return 'error';
      return this.client ? 'meshing' : 'connecting';
    }
    if (this.paused) return 'paused';
    const busy = this.pending || this.inFlight;
    if (!busy && s.converged) return 'converged'; // a version may converge with no frame
    if (busy || !s.mesh.synchronized || s.mesh.functionVersion < (s.state?.version ?? 0)) return 'meshing';
    return 'refining';
  }

  /** True when the current version is final and has no triangle in the box. */
  get empty() {
    return this.status === 'converged' && this.triangles === 0;
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
        if (this.client === client) this.#failed(error, { expression });
        return;
      }
    }
    this.creating = false;
    if (this.client !== client || this.expression === '') {
      session.close().catch(() => {}); // detached or deleted meanwhile
      return;
    }
    this.session = session;
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
    session.on('closed', (m) => {
      if (!current()) return;
      this.session = null;
      this.#note(`closed (${m.reason})`);
      this.onChange(this, 'session');
    });
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
    if (this.inFlight || this.waitingFor || !this.session || !this.pending) return;
    const session = this.session;
    const fields = this.pending;
    this.pending = null;
    this.inFlight = true;
    try {
      const state = await session.update(fields);
      if (fields.expression !== undefined) this.error = null;
      if (this.session === session) this.#waitForMesh(state.version);
      this.onChange(this, 'state');
    } catch (error) {
      const missing = missingParameters(error).filter((name) => !(name in (fields.parameters ?? {})));
      if (fields.expression !== undefined && missing.length > 0) {
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

/** Later fields win; parameters and constraints merge name by name. */
export function mergeFields(earlier, later) {
  if (!earlier) return { ...later };
  const merged = { ...earlier, ...later };
  if (earlier.parameters || later.parameters) merged.parameters = { ...earlier.parameters, ...later.parameters };
  if (earlier.constraints || later.constraints) merged.constraints = { ...earlier.constraints, ...later.constraints };
  return merged;
}

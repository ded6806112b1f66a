// The viewer's session logic: one connection, one session, and the user's edits turned into
// `update` requests.
//
// Frames are applied a few milliseconds per animation frame (drainFrames), not on receipt.
// Edits are coalesced: at most one update is in flight; edits made meanwhile (a slider being
// dragged) are merged and sent when its reply arrives, so the surface follows the latest value at
// the pace of the round trip instead of queueing every intermediate one. The state the server
// reports (created/updated) is what the panel then shows: the parameter list, constraints, box.

import { connect } from 'isomesh-client';

import { missingParameters, parameterNames, valuesFor } from './parameters.js';

const RECONNECT_MS = [500, 1000, 2000, 5000, 10000];

export class App {
  /**
   * @param {{panel: Panel, viewer: Viewer, url: string, decoder: object, initial: object}} options
   *   initial: {expression, parameters, box, constraints} of the first session
   */
  constructor({ panel, viewer, url, decoder, initial }) {
    this.panel = panel;
    this.viewer = viewer;
    this.url = url;
    this.decoder = decoder;
    this.wanted = { ...initial, parameters: { ...(initial.parameters ?? {}) } };
    this.client = null;
    this.session = null;
    this.status = 'connecting';
    this.lastError = null; // {code, message, column} of the last rejected request
    this.errorMax = null;
    this.pending = null; // fields of the next update
    this.inFlight = false;
    this.paused = false;
    this.reconnects = 0;
    this.framedBox = null;
    /** The last 200 session events, for diagnostics (window.isomesh.journal). */
    this.journal = [];
  }

  async start() {
    this.#setStatus('connecting');
    try {
      this.client = await connect(this.url, { decoder: this.decoder, deferFrames: true });
    } catch (error) {
      this.#disconnected(error.message);
      return;
    }
    this.reconnects = 0;
    this.client.on('close', () => this.#disconnected('connection closed'));
    // The library reconnects and subscribes again by itself; the status line shows it meanwhile.
    this.client.on('disconnected', () => this.#setStatus('disconnected', 'reconnecting'));
    this.client.on('reconnected', () => (this.session ? this.#refreshStatus() : this.#createSession()));
    this.client.on('error', (error) => console.warn('isomesh:', error));
    await this.#createSession();
  }

  /**
   * Applies received frames for at most `budgetMs` (called once per animation frame, so that
   * decoding never stalls rendering); returns true when any was applied.
   */
  drainFrames(budgetMs) {
    const client = this.client;
    if (!client || client.pendingFrames === 0) return false;
    client.drainFrames(performance.now() + budgetMs);
    return true;
  }

  // ---- user edits ------------------------------------------------------------------------------

  setEquation(text) {
    if (text === '') return;
    const parameters = valuesFor(parameterNames(text), this.wanted.parameters);
    this.wanted.expression = text;
    Object.assign(this.wanted.parameters, parameters);
    this.#change({ expression: text, parameters });
  }

  setParameter(name, value) {
    this.wanted.parameters[name] = value;
    this.#change({ parameters: { [name]: value } });
  }

  setConstraints(constraints) {
    this.wanted.constraints = { ...this.wanted.constraints, ...constraints };
    this.#change({ constraints });
  }

  setBox(box) {
    this.wanted.box = box;
    this.#change({ box });
  }

  showExample(example) {
    this.wanted.expression = example.expression;
    this.wanted.box = example.box;
    Object.assign(this.wanted.parameters, example.parameters ?? {});
    const parameters = valuesFor(parameterNames(example.expression), this.wanted.parameters);
    this.panel.setEquation(example.expression);
    this.framedBox = null; // aim the camera at the new box once the server accepts it
    this.#change({ expression: example.expression, parameters, box: example.box });
  }

  async togglePause() {
    if (!this.session) return;
    this.paused = !this.paused;
    this.panel.setPaused(this.paused);
    await (this.paused ? this.session.pause() : this.session.resume()).catch((e) => this.#requestFailed(e, {}));
    this.#refreshStatus();
  }

  // ---- session ---------------------------------------------------------------------------------

  async #createSession() {
    const { expression, parameters, box, constraints } = this.wanted;
    this.#setStatus('meshing');
    let names = parameterNames(expression);
    for (let attempt = 0; ; ++attempt) {
      try {
        this.session = await this.client.create({ expression, parameters: valuesFor(names, parameters), box, constraints });
        break;
      } catch (error) {
        const missing = missingParameters(error).filter((name) => !names.includes(name));
        if (attempt === 0 && missing.length > 0) {
          names = [...names, ...missing];
          continue;
        }
        this.session = null;
        this.#requestFailed(error, { expression });
        return;
      }
    }
    this.panel.clearError();
    this.lastError = null;
    this.#watch(this.session);
    this.viewer.showSlots(this.session.mesh.slots);
    this.#applyState(this.session.state);
    this.#pump();
  }

  #watch(session) {
    const note = (entry) => {
      this.journal.push(entry);
      if (this.journal.length > 200) this.journal.shift();
    };
    const noteFrame = ({ header: h, removed, triangleIds }) =>
      note(`${h.kind} s${h.sequence} v${h.functionVersion} -${removed.length} +${triangleIds.length}${h.converged ? ' converged' : ''}`);
    session.on('state', (state) => {
      note(`state v${state.version} ${JSON.stringify(state.parameters)}`);
      this.#refreshStatus();
    });
    session.on('keyframe', (frame) => {
      noteFrame(frame);
      this.#meshChanged();
    });
    session.on('delta', (frame) => {
      noteFrame(frame);
      this.#meshChanged();
    });
    session.on('resync', ({ reason }) => note(`resync (${reason})`));
    session.on('firstMesh', () => this.#refreshStatus());
    session.on('progress', (m) => {
      if (m.version === session.state?.version) this.errorMax = m.error_max;
      this.#refreshStatus();
    });
    session.on('converged', (m) => {
      note(`converged v${m.version} s${m.sequence}`);
      if (m.version === session.state?.version) this.errorMax = m.error_max;
      this.#refreshStatus();
    });
    session.on('error', (error) => {
      this.lastError = { code: error.code, message: error.message, column: error.column ?? null };
      this.panel.showError(this.wanted.expression, error.message, error.column);
      this.#refreshStatus();
    });
    session.on('closed', (m) => {
      if (this.session === session) this.session = null;
      if (m.reason === 'lost' && this.client?.connected) return this.#createSession(); // server forgot it
      this.#setStatus(m.reason === 'shutdown' ? 'disconnected' : 'closed');
    });
  }

  #change(fields) {
    if (!this.session) {
      // No session yet (its creation failed, e.g. on a bad equation): try again with everything.
      if (this.client && !this.client.closed && fields.expression !== undefined) this.#createSession();
      return;
    }
    this.pending = mergeFields(this.pending, fields);
    this.#setStatus('meshing');
    this.#pump();
  }

  async #pump() {
    if (this.inFlight || !this.session || !this.pending) return;
    const fields = this.pending;
    this.pending = null;
    this.inFlight = true;
    try {
      const state = await this.session.update(fields);
      if (fields.expression !== undefined) {
        this.panel.clearError();
        this.lastError = null;
      }
      this.#applyState(state);
    } catch (error) {
      const missing = missingParameters(error).filter((name) => !(name in (fields.parameters ?? {})));
      if (fields.expression !== undefined && missing.length > 0) {
        this.#change({ ...fields, parameters: { ...fields.parameters, ...valuesFor(missing, this.wanted.parameters) } });
      } else {
        this.#requestFailed(error, fields);
      }
    } finally {
      this.inFlight = false;
    }
    this.#pump();
    this.#refreshStatus();
  }

  #applyState(state) {
    this.wanted.expression = state.expression ?? this.wanted.expression;
    this.wanted.box = state.box;
    this.wanted.constraints = { ...state.constraints };
    if (!this.pending?.parameters) Object.assign(this.wanted.parameters, state.parameters);
    this.panel.setParameters(state.parameters);
    this.panel.setConstraints(state.constraints ?? {});
    this.panel.setBox(state.box);
    if (this.panel.equation.value.trim() === '') this.panel.setEquation(this.wanted.expression);
    const boxKey = state.box.join(',');
    this.viewer.setBox(state.box, { frame: this.framedBox === null });
    this.framedBox = boxKey;
    this.#refreshStatus();
  }

  #requestFailed(error, fields) {
    this.lastError = { code: error.code ?? 'internal', message: error.message, column: error.column ?? null };
    const text = fields.expression ?? this.wanted.expression;
    this.panel.showError(text, error.message, error.column);
    this.#refreshStatus();
  }

  #meshChanged() {
    this.viewer.requestRender();
    this.#refreshStatus();
  }

  #disconnected(reason) {
    this.session = null;
    this.client = null;
    this.inFlight = false;
    this.#setStatus('disconnected', reason);
    const delay = RECONNECT_MS[Math.min(this.reconnects++, RECONNECT_MS.length - 1)];
    setTimeout(() => this.start(), delay);
  }

  // ---- status ----------------------------------------------------------------------------------

  #refreshStatus() {
    if (this.client && !this.client.connected) return this.#setStatus('disconnected', 'reconnecting');
    const s = this.session;
    if (!s) {
      this.#setStatus(this.lastError ? 'error' : this.status);
      return;
    }
    let status = 'refining';
    const busy = this.pending || this.inFlight;
    if (this.paused) status = 'paused';
    else if (!busy && s.converged) status = 'converged'; // a version may converge with no frame
    else if (busy || !s.mesh.synchronized || s.mesh.functionVersion < (s.state?.version ?? 0)) status = 'meshing';
    this.#setStatus(status);
  }

  #setStatus(status, detail = '') {
    this.status = status;
    this.statusDetail = detail;
    this.onStatus?.(this);
  }

  /** What the status line and tests read. */
  snapshot() {
    const s = this.session;
    return {
      status: this.status,
      detail: this.statusDetail,
      session: s?.id ?? null,
      version: s?.state?.version ?? null,
      sequence: s?.mesh.sequence ?? null,
      triangles: s?.mesh.triangleCount ?? 0,
      errorMax: this.errorMax,
      bytesReceived: this.client?.bytesReceived ?? 0,
      firstMeshMs: s?.stats.firstMeshMs ?? null,
      serverFirstMeshMs: s?.lastConverged?.first_mesh_ms ?? null,
      expression: this.wanted.expression,
      parameters: { ...(s?.state?.parameters ?? {}) },
      box: s?.state?.box ?? this.wanted.box,
      constraints: s?.state?.constraints ?? null,
      error: this.lastError,
    };
  }
}

/** Later fields win; parameters and constraints merge name by name. */
function mergeFields(earlier, later) {
  if (!earlier) return { ...later };
  const merged = { ...earlier, ...later };
  if (earlier.parameters || later.parameters) merged.parameters = { ...earlier.parameters, ...later.parameters };
  if (earlier.constraints || later.constraints) merged.constraints = { ...earlier.constraints, ...later.constraints };
  return merged;
}

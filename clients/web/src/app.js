// The viewer's scene: one connection to the server, any number of surfaces (a row of the object
// list each, with its own session), and the values they share, as GeoGebra shares them between
// objects: the parameters (one slider per name, whatever surfaces use it), the view box and the
// detail constraints. It turns what the user does into Surface calls and shows what the surfaces
// report: the rows' progress and messages, the sliders, the status line. The connection
// (connection.js) reconnects by itself and keeps every row's session.

import { RECONNECT_DELAYS_MS, connect } from 'isomesh-client';

import { Connection } from './connection.js';
import { EMPTY_MESSAGE, prepareEquation } from './equation_check.js';
import { endedMessage, outcomeNotes, uncertain } from './outcome.js';
import { parameterNames } from './parameters.js';
import { Surface } from './surface.js';
import { MAX_SURFACES } from './url_state.js';

export const PALETTE = ['#3d7fd6', '#d9553d', '#3f9e4d', '#8e5bd0', '#1f9fa5', '#c98a1b', '#d6457e', '#5f6b7a'];
const STATUS_ORDER = ['disconnected', 'connecting', 'meshing', 'resolving', 'refining', 'paused', 'converged', 'ended'];

export class App {
  /**
   * @param {object} o
   * @param {string} o.url the server's WebSocket URL
   * @param {object} o.decoder a DracoMeshDecoder
   * @param {Viewer} o.viewer
   * @param {ObjectList} o.objects
   * @param {SliderPanel} o.sliders
   * @param {Panel} o.panel
   * @param {object} o.state the scene to start with (url_state.js's shape)
   */
  constructor({ url, decoder, viewer, objects, sliders, panel, state }) {
    Object.assign(this, { url, decoder, viewer, objects, sliders, panel });
    this.connection = new Connection({
      connect,
      url,
      options: { decoder, deferFrames: true },
      delaysMs: RECONNECT_DELAYS_MS,
      onChange: () => this.#refresh(),
    });
    this.parameters = { ...(state.parameters ?? {}) };
    this.box = state.box;
    this.constraints = { ...(state.constraints ?? {}) };
    this.paused = false;
    this.rows = [];
    this.activeRow = null;
    /** Called when something the URL holds changed. */
    this.onStateChange = null;
    /** Called when the status line or the rows need redrawing (at most once per animation frame). */
    this.onStatus = null;
    this.refreshQueued = false;
    for (const s of state.surfaces ?? []) this.addSurface(s);
  }

  /** Connects (trying until the server answers) and gives every row its session. */
  async start() {
    this.#refresh();
    const client = await this.connection.open();
    if (!client) return;
    client.on('error', (error) => console.warn('isomesh:', error));
    for (const row of this.rows) row.surface.attach(client);
    this.#refresh();
  }

  /** The connection's client once open (the same object across reconnections), else null. */
  get client() {
    return this.connection.client;
  }

  /** The values every surface shares, for a new session. */
  shared() {
    return { parameters: this.parameters, box: this.box, constraints: this.constraints };
  }

  // ---- rows ------------------------------------------------------------------------------------

  /** A new row (and surface); `focus` puts the cursor in its equation field. */
  addSurface({ expression = '', color = null, visible = true } = {}, { focus = false } = {}) {
    if (this.rows.length >= MAX_SURFACES) return null;
    const used = new Set(this.rows.map((r) => r.view.color));
    color ??= PALETTE.find((c) => !used.has(c)) ?? PALETTE[this.rows.length % PALETTE.length];
    const prepared = expression === '' ? { ok: true, expression: '', notes: [] } : prepareEquation(expression);
    const row = { notes: prepared.notes ?? [], localError: null, shownError: null };
    row.view = this.objects.addRow({ expression: prepared.expression ?? expression, color, visible });
    row.view.input.addEventListener('focus', () => (this.activeRow = row));
    row.mesh = this.viewer.addSurface(color);
    row.mesh.setVisible(visible);
    row.surface = new Surface({
      expression: prepared.ok ? prepared.expression : '',
      shared: () => this.shared(),
      onChange: (surface, what) => this.#surfaceChanged(row, what),
    });
    this.rows.push(row);
    this.activeRow ??= row;
    if (this.client) row.surface.attach(this.client);
    if (focus) {
      row.view.input.focus();
      this.activeRow = row;
    }
    this.panel.setCanAdd(this.rows.length < MAX_SURFACES, `At most ${MAX_SURFACES} surfaces`);
    this.#stateChanged();
    return row;
  }

  rowOf(view) {
    return this.rows.find((r) => r.view === view);
  }

  async removeSurface(row) {
    const i = this.rows.indexOf(row);
    if (i < 0) return;
    this.rows.splice(i, 1);
    if (this.activeRow === row) this.activeRow = this.rows[Math.min(i, this.rows.length - 1)] ?? null;
    this.objects.removeRow(row.view);
    row.mesh.dispose();
    this.panel.setCanAdd(true, '');
    this.#updateSliders();
    this.#stateChanged();
    await row.surface.close();
  }

  /** The user pressed Enter in a row's equation field. */
  submitEquation(row, text) {
    this.activeRow = row;
    const prepared = prepareEquation(text);
    if (!prepared.ok) {
      row.localError = { message: EMPTY_MESSAGE };
      this.#refresh();
      return;
    }
    row.localError = null;
    row.notes = prepared.notes;
    if (prepared.expression !== text.trim()) row.view.setEquation(prepared.expression);
    for (const name of parameterNames(prepared.expression)) this.parameters[name] ??= 1; // GeoGebra's start
    row.surface.setExpression(prepared.expression);
    this.#updateSliders();
    this.#stateChanged();
  }

  setColor(row, color) {
    row.mesh.setColor(color);
    this.#stateChanged();
  }

  setVisible(row, on) {
    row.mesh.setVisible(on);
    this.#stateChanged();
  }

  // ---- shared values ---------------------------------------------------------------------------

  setParameter(name, value) {
    this.parameters[name] = value;
    for (const row of this.rows) row.surface.setParameters({ [name]: value });
    this.#stateChanged();
  }

  /** A box the user typed: the camera follows it (as GeoGebra's view follows its axes' ranges). */
  setBox(box) {
    this.box = box;
    this.viewer.setBox(box, { frame: 'keep' });
    for (const row of this.rows) row.surface.setBox(box);
    this.#stateChanged();
  }

  setConstraints(constraints) {
    this.constraints = { ...this.constraints, ...constraints };
    for (const row of this.rows) row.surface.setConstraints(constraints);
    this.#stateChanged();
  }

  /** A gallery example replaces the active row's equation, and sets its parameters and box. */
  showExample(example) {
    const row = this.activeRow ?? this.rows[0] ?? this.addSurface();
    Object.assign(this.parameters, example.parameters ?? {});
    for (const [name, value] of Object.entries(example.parameters ?? {})) this.sliders.setValue(name, value);
    this.box = example.box;
    this.panel.setBox(example.box);
    this.viewer.setBox(example.box, { frame: true });
    for (const other of this.rows) {
      if (other !== row) {
        other.surface.setBox(example.box);
        other.surface.setParameters(example.parameters ?? {});
      }
    }
    row.view.setEquation(example.expression);
    row.surface.setBox(example.box);
    this.submitEquation(row, example.expression);
  }

  togglePause() {
    this.paused = !this.paused;
    this.panel.setPaused(this.paused);
    for (const row of this.rows) row.surface.setPaused(this.paused);
  }

  // ---- reading ---------------------------------------------------------------------------------

  /** What the URL keeps (url_state.js's shape, without camera and display). */
  state() {
    const names = this.sliderNames();
    return {
      surfaces: this.rows.map((r) => ({ expression: r.view.input.value.trim(), color: r.view.color, visible: r.view.visible })),
      parameters: Object.fromEntries(names.map((n) => [n, this.parameters[n] ?? 1])),
      sliders: Object.fromEntries(Object.entries(this.sliders.ranges()).filter(([n]) => names.includes(n))),
      box: this.box,
      constraints: this.constraints,
    };
  }

  /** Parameter names of every surface, in order of first use. */
  sliderNames() {
    const names = [];
    for (const row of this.rows) for (const name of row.surface.parameterNames) if (!names.includes(name)) names.push(name);
    return names;
  }

  /** Visible surfaces as exported: [{name, color, positions, normals, indices}]. */
  exportSurfaces() {
    return this.rows
      .filter((r) => r.view.visible && r.surface.session && r.surface.triangles > 0)
      .map((r) => ({ name: r.surface.session.state?.expression ?? r.surface.expression, color: r.view.color, ...r.surface.session.mesh.toIndexed() }));
  }

  /** The status line's state: the most pressing of the rows'. */
  get status() {
    if (this.connection.state !== 'open') return this.connection.state;
    const states = this.rows.map((r) => r.surface.status);
    const live = states.filter((s) => STATUS_ORDER.includes(s));
    if (live.length > 0) return STATUS_ORDER.find((s) => live.includes(s));
    if (states.includes('error')) return 'error';
    return 'empty';
  }

  /** What the status line and tests read. */
  snapshot() {
    const active = this.activeRow ?? this.rows[0];
    const a = active?.surface.snapshot();
    const surfaces = this.rows.map((r) => ({
      ...r.surface.snapshot(),
      color: r.view.color,
      visible: r.view.visible,
      notes: [...r.view.notes.children].map((li) => li.textContent),
      message: r.view.errorBox.hidden ? null : r.view.errorMessage.textContent,
    }));
    const errors = this.rows.map((r) => r.surface.errorMax).filter((e) => e !== null);
    return {
      status: this.status,
      detail: this.connection.detail,
      triangles: this.rows.reduce((sum, r) => sum + r.surface.triangles, 0),
      errorMax: errors.length > 0 ? Math.max(...errors) : null,
      bytesReceived: this.client?.bytesReceived ?? 0,
      firstMeshMs: a?.firstMeshMs ?? null,
      session: a?.session ?? null,
      version: a?.version ?? null,
      expression: a?.expression ?? null,
      parameters: Object.fromEntries(this.sliderNames().map((n) => [n, this.parameters[n]])),
      box: this.box,
      constraints: a?.constraints ?? this.constraints,
      error: active?.surface.error ?? null,
      surfaces,
    };
  }

  // ---- internals -------------------------------------------------------------------------------

  #surfaceChanged(row, what) {
    const surface = row.surface;
    if (what === 'session') row.mesh.showSlots(surface.session?.mesh.slots ?? null);
    if (what === 'state' && surface.session?.state) this.#adoptState(surface.session.state);
    if (what === 'mesh') this.viewer.requestRender();
    if (what === 'state' || what === 'session') this.#updateSliders();
    this.#refresh();
  }

  /** The server's values: parameters it added (a name the client-side scan missed), constraints in force. */
  #adoptState(state) {
    for (const [name, value] of Object.entries(state.parameters)) this.parameters[name] ??= value;
    if (state.constraints) {
      const c = state.constraints;
      this.constraints = { triangles: c.triangles, max_error: c.max_error, error_measure: c.error_measure, ...this.constraints };
      this.panel.setConstraints({ ...c, ...this.constraints });
    }
  }

  #updateSliders() {
    this.sliders.setNames(this.sliderNames(), this.parameters);
  }

  /** Redraws the rows and the status line at the next animation frame (once, however many calls). */
  #refresh() {
    if (this.refreshQueued) return;
    this.refreshQueued = true;
    requestAnimationFrame(() => {
      this.refreshQueued = false;
      for (const row of this.rows) this.#showRow(row);
      this.onStatus?.(this);
    });
  }

  #showRow(row) {
    const s = row.surface;
    const finished = s.finished;
    const budget = s.session?.state?.constraints?.triangles ?? 0;
    row.view.setProgress({ status: s.status, triangles: s.triangles, budget, uncertain: uncertain(finished) });
    const error = row.localError ?? s.error;
    if (error !== row.shownError) {
      row.shownError = error;
      if (error) row.view.showError(error.text ?? '', error.message, error.column ?? null);
      else row.view.clearError();
    }
    const said = s.ended ? [endedMessage(s.ended)] : outcomeNotes(finished, s.triangles, budget);
    row.view.setNotes(error ? row.notes : [...row.notes, ...said]);
  }

  #stateChanged() {
    this.onStateChange?.();
    this.#refresh();
  }
}

// <isomesh-surface>: an implicit surface in any page, for GeoGebra-like apps.
//
//   <script type="module" src="/isomesh-surface.js"></script>
//   <isomesh-surface equation="x^2+y^2+z^2=a" a="4"></isomesh-surface>
//
// Attributes (all optional but `equation`; changing one updates the surface live):
//   equation    the equation, as the viewer reads it (capital X, Y, Z are x, y, z)
//   NAME="4"    the value of parameter NAME (HTML lowercases attribute names, so this form suits
//               lowercase names; `parameters` takes any)
//   parameters  "R: 2, r: 0.7": values of parameters, names as written
//   box         "x0,x1,y0,y1,z0,z1" (default -3,3,-3,3,-3,3)
//   budget      the triangle budget;  color  a CSS colour;  colormode  uniform | height | normal
//   axes, grid  "off" hides them (default: shown);  status  shows the triangle count line
//   server      the server's WebSocket URL (default: /ws on the server this script came from)
// Events: `converged` and `error` (detail: the element's snapshot()). The element fills its box
// (display: block, 300 px high unless styled); orbit, zoom and pan as in the viewer.
// The status line also appears, whatever `status` says, for what the user should know: an error,
// no surface in the box, a region rather than a surface, a budget below what the shape needs, a
// lost connection (the client library reconnects and the surface keeps its session).

import { RECONNECT_DELAYS_MS, connect, loadDracoDecoder } from 'isomesh-client';
import dracoWasmUrl from 'draco3d/draco_decoder.wasm?url';

import { Connection } from './connection.js';
import { prepareEquation } from './equation_check.js';
import { endedMessage, outcomeNotes, uncertain } from './outcome.js';
import { parameterAttributes } from './parameters.js';
import { FramePump } from './frame_pump.js';
import { Surface } from './surface.js';
import { validBox } from './url_state.js';
import { DARK_THEME, LIGHT_THEME, Viewer } from './viewer.js';

const DEFAULT_BOX = [-3, 3, -3, 3, -3, 3];
const OWN_ATTRIBUTES = new Set(['equation', 'parameters', 'box', 'budget', 'color', 'colormode', 'axes', 'grid', 'status', 'server']);
/** The status line's words for a surface state, where its name is not plain enough. */
const STATUS_WORDS = { meshing: 'finding the shape…', resolving: 'finding the shape…' };

let decoderPromise = null;
const sharedDecoder = () => (decoderPromise ??= loadDracoDecoder({ locateFile: () => dracoWasmUrl }));

/** The default server: /ws on the origin this module was loaded from. */
function defaultServer() {
  const here = new URL(import.meta.url);
  here.pathname = '/ws';
  here.search = '';
  here.hash = '';
  here.protocol = here.protocol === 'https:' ? 'wss:' : 'ws:';
  return here.href;
}

const STYLE = `
:host { display: block; position: relative; height: 300px; min-height: 120px; }
.host { position: absolute; inset: 0; }
.host canvas { display: block; width: 100%; height: 100%; touch-action: none; }
.status { position: absolute; left: 6px; bottom: 6px; padding: 2px 8px; border-radius: 5px;
  font: 12px system-ui, sans-serif; background: rgba(255,255,255,0.85); color: #374151; pointer-events: none; }
.status.error { color: #c62828; }
.status.note { color: #8a5300; }
.status[hidden] { display: none; }
@media (prefers-color-scheme: dark) { .status { background: rgba(28,32,39,0.85); color: #d5dae1; } .status.error { color: #ff7b72; } .status.note { color: #e3b341; } }
`;

export class IsomeshSurfaceElement extends HTMLElement {
  constructor() {
    super();
    this.viewer = null;
    this.surface = null;
    this.connection = null;
    this.sent = null; // {expression, parameters, box, budget} last sent
    this.gone = false;
    this.convergedVersion = null;
  }

  connectedCallback() {
    if (this.viewer) return;
    this.gone = false;
    const root = this.shadowRoot ?? this.attachShadow({ mode: 'open' });
    const style = document.createElement('style');
    style.textContent = STYLE;
    const host = document.createElement('div');
    host.className = 'host';
    this.statusLine = document.createElement('div');
    this.statusLine.className = 'status';
    this.statusLine.setAttribute('role', 'status');
    this.statusLine.hidden = true;
    root.replaceChildren(style, host, this.statusLine);
    this.viewer = new Viewer(host);
    this.view = this.viewer.addSurface(this.getAttribute('color') ?? '#3d7fd6');
    const dark = matchMedia('(prefers-color-scheme: dark)');
    this.viewer.setTheme(dark.matches ? DARK_THEME : LIGHT_THEME);
    this.#applyDisplay();
    this.viewer.setBox(this.#box(), { frame: true });
    this.surface = new Surface({
      shared: () => ({ parameters: this.#parameters(), box: this.#box(), constraints: this.#constraints() }),
      onChange: (surface, what) => this.#changed(what),
    });
    const pump = new FramePump({ drain: (deadline) => this.client?.drainFrames(deadline), pending: () => this.client?.pendingFrames ?? 0 });
    this.viewer.hooks.beforeRender = () => pump.onAnimationFrame();
    this.onVisibility = () => pump.visibilityChanged();
    document.addEventListener('visibilitychange', this.onVisibility);
    this.observer = new MutationObserver(() => this.#attributesChanged());
    this.observer.observe(this, { attributes: true });
    this.#attributesChanged();
    this.#connect();
  }

  disconnectedCallback() {
    this.gone = true;
    this.observer?.disconnect();
    document.removeEventListener('visibilitychange', this.onVisibility);
    this.surface?.close();
    this.connection?.stop();
    this.viewer?.dispose();
    this.viewer = null;
    this.connection = null;
  }

  /** The connection's client once open, else null. */
  get client() {
    return this.connection?.client ?? null;
  }

  /** The state, as the viewer's window.isomesh.snapshot() gives it for one surface. */
  snapshot() {
    return this.surface?.snapshot() ?? null;
  }

  /** Connects (trying until the server answers); the client library then reconnects by itself. */
  async #connect() {
    let decoder;
    try {
      decoder = await sharedDecoder();
    } catch (error) {
      this.#showStatus(`cannot decode meshes: ${error.message}`, 'error');
      return;
    }
    if (this.gone) return;
    const connection = new Connection({
      connect,
      url: this.getAttribute('server') ?? defaultServer(),
      options: { decoder, deferFrames: true },
      delaysMs: RECONNECT_DELAYS_MS,
      onChange: () => this.#changed('status'),
    });
    this.connection = connection;
    const client = await connection.open();
    if (client && !this.gone) this.surface.attach(client);
  }

  #attributesChanged() {
    if (!this.surface) return;
    const prepared = prepareEquation(this.getAttribute('equation') ?? '');
    const now = { expression: prepared.ok ? prepared.expression : '', parameters: this.#parameters(), box: this.#box(), budget: this.#constraints().triangles };
    const before = this.sent;
    this.sent = now;
    this.view.setColor(this.getAttribute('color') ?? '#3d7fd6');
    this.#applyDisplay();
    if (!prepared.ok) {
      this.#showStatus(prepared.message, 'error');
      return;
    }
    if (!before || before.expression !== now.expression) {
      this.surface.setExpression(now.expression);
      if (!before) return; // the first session is created with everything on attach
    }
    const changed = Object.fromEntries(Object.entries(now.parameters).filter(([k, v]) => before.parameters[k] !== v));
    if (Object.keys(changed).length > 0) this.surface.setParameters(changed);
    if (before.box.join() !== now.box.join()) {
      this.surface.setBox(now.box);
      this.viewer.setBox(now.box, { frame: true });
    }
    if (now.budget !== undefined && before.budget !== now.budget) this.surface.setConstraints({ triangles: now.budget });
  }

  #applyDisplay() {
    this.viewer.setColorMode(this.getAttribute('colormode') ?? 'uniform');
    this.viewer.setShown({ axes: this.getAttribute('axes') !== 'off', grid: this.getAttribute('grid') !== 'off', box: this.getAttribute('axes') !== 'off' });
  }

  #parameters() {
    return parameterAttributes(this.attributes, this.getAttribute('parameters'), OWN_ATTRIBUTES);
  }

  #box() {
    const box = (this.getAttribute('box') ?? '').split(',').map(Number);
    return validBox(box) ? box : DEFAULT_BOX;
  }

  #constraints() {
    const budget = Number(this.getAttribute('budget'));
    return Number.isInteger(budget) && budget >= 1 ? { triangles: budget } : {};
  }

  #changed(what) {
    const s = this.surface;
    if (!s) return;
    if (what === 'session') this.view.showSlots(s.session?.mesh.slots ?? null);
    this.viewer?.requestRender();
    const finished = s.finished;
    const notes = s.ended ? [endedMessage(s.ended)] : outcomeNotes(finished, s.triangles, s.session?.state?.constraints?.triangles ?? 0);
    const connection = this.connection;
    if (connection && connection.state === 'disconnected') {
      this.#showStatus(`disconnected (${connection.detail}) · ${s.triangles} triangles`, 'note');
    } else if (s.error) {
      this.#showStatus(s.error.message, 'error');
      if (what === 'error') this.dispatchEvent(new CustomEvent('error', { detail: this.snapshot() }));
    } else if (notes.length > 0) {
      this.#showStatus(notes[0], 'note');
    } else {
      const approximate = uncertain(finished) ? ' · approximate in places' : '';
      this.#showStatus(`${s.triangles} triangles · ${STATUS_WORDS[s.status] ?? s.status}${approximate}`, 'info');
    }
    const version = s.session ? `${s.session.id}:${s.session.state?.version}` : null;
    if (s.status === 'converged' && version !== this.convergedVersion) {
      this.convergedVersion = version; // once per function version
      this.dispatchEvent(new CustomEvent('converged', { detail: this.snapshot() }));
    }
  }

  /** `kind`: 'error' or 'note' (always shown), 'info' (shown with the `status` attribute). */
  #showStatus(text, kind) {
    this.statusLine.textContent = text;
    this.statusLine.classList.toggle('error', kind === 'error');
    this.statusLine.classList.toggle('note', kind === 'note');
    this.statusLine.hidden = kind === 'info' && !this.hasAttribute('status');
  }
}

if (!customElements.get('isomesh-surface')) customElements.define('isomesh-surface', IsomeshSurfaceElement);

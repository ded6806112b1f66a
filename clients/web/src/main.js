// The isomesh browser viewer: wires the panel, the object list, the sliders, the 3D view and the
// scene together; keeps the scene in the URL (and the last one in localStorage, for a new tab);
// and exposes the viewer's state as `window.isomesh` (read by the browser test, handy in the
// console).
//
// URL options: ?server=ws://host:port/ws (default: /ws of the page's own server), and the scene
// (url_state.js: eq=EQUATION, p=a:4, box=..., cam=...; the legacy ?expr=EQUATION still works).

import { loadDracoDecoder } from 'isomesh-client';
import dracoWasmUrl from 'draco3d/draco_decoder.wasm?url';

import { App } from './app.js';
import { download, toGlb, toObj, toStl } from './export.js';
import { FramePump } from './frame_pump.js';
import { GALLERY } from './gallery.js';
import { bindShortcuts } from './keyboard.js';
import { ObjectList } from './object_list.js';
import { Panel } from './panel.js';
import { SliderPanel } from './sliders.js';
import { COLOR_MODES, DEFAULT_SHOW, decodeState, encodeState } from './url_state.js';
import { DARK_THEME, LIGHT_THEME, Viewer } from './viewer.js';

const STORAGE_KEY = 'isomesh.viewer.scene';
/** The status line's words for states whose name is not plain enough. */
const STATUS_WORDS = { resolving: 'finding the shape', ended: 'session ended' };
const URL_WRITE_DELAY_MS = 250;
const $ = (selector) => document.querySelector(selector);

const query = new URLSearchParams(location.search);
const defaultUrl = `${location.protocol === 'https:' ? 'wss:' : 'ws:'}//${location.host}/ws`;
const url = query.get('server') ?? defaultUrl;
const initial = startingScene();

const statusLine = $('#status');
let app = null;
let pump = null;
const display = { colorMode: 'uniform', show: [...DEFAULT_SHOW], wireframe: false, ...initial.display };

const viewer = new Viewer($('#canvas-host'));
const sliders = new SliderPanel($('#parameters .sliders'), $('#parameters .empty'), {
  onValue: (name, value) => app?.setParameter(name, value),
  onRange: () => sceneChanged(),
});
const objects = new ObjectList($('#object-list'), {
  onEquation: (view, text) => app?.submitEquation(app.rowOf(view), text),
  onColor: (view, color) => app?.setColor(app.rowOf(view), color),
  onVisible: (view, on) => app?.setVisible(app.rowOf(view), on),
  onDelete: (view) => app?.removeSurface(app.rowOf(view)),
});
const panel = new Panel({
  onBudget: (triangles) => app?.setConstraints({ triangles }),
  onMaxError: (value) => app?.setConstraints({ max_error: value }),
  onErrorMeasure: (name) => app?.setConstraints({ error_measure: name }),
  onBox: (box) => app?.setBox(box),
  onGallery: (example) => app?.showExample(example),
  onColorMode: (mode) => setDisplay({ colorMode: mode }),
  onShown: (shown) => setDisplay({ show: DEFAULT_SHOW.filter((k) => shown[k] ?? display.show.includes(k)) }),
  onWireframe: (on) => setDisplay({ wireframe: on }),
  onResetView: () => viewer.frameBox(),
  onPause: () => app?.togglePause(),
  onAddSurface: () => app?.addSurface({}, { focus: true }),
  onCopyLink: () => copyLink(),
  onExport: (format) => exportAs(format),
  onHelp: () => $('#help').showModal(),
  onPanelShown: (on) => showPanel(on),
});

/** The scene of the URL, else the last one of this browser (a new tab), else the first example. */
function startingScene() {
  const fromUrl = decodeState(location.search);
  if (fromUrl) return withDefaults(fromUrl);
  const stored = decodeState(localStorage.getItem(STORAGE_KEY) ?? '');
  if (stored) return withDefaults(stored);
  const example = GALLERY[0];
  return withDefaults({ surfaces: [{ expression: example.expression }], parameters: example.parameters, box: example.box });
}

function withDefaults(state) {
  return { surfaces: [{ expression: '' }], box: [-3, 3, -3, 3, -3, 3], ...state };
}

function setDisplay(changes) {
  Object.assign(display, changes);
  viewer.setColorMode(display.colorMode);
  viewer.setShown(Object.fromEntries(DEFAULT_SHOW.map((k) => [k, display.show.includes(k)])));
  viewer.setWireframe(display.wireframe);
  panel.setDisplay(display);
  sceneChanged();
}

function showPanel(on) {
  document.body.classList.toggle('panel-hidden', !on);
  (on ? $('#hide-panel') : $('#show-panel')).focus();
}

// ---- the URL ----------------------------------------------------------------------------------

let urlTimer = null;
/** Writes the URL once changes have stopped for URL_WRITE_DELAY_MS (a drag writes it once, at its end). */
function sceneChanged() {
  if (!app) return;
  clearTimeout(urlTimer);
  urlTimer = setTimeout(() => {
    urlTimer = null;
    writeUrl();
  }, URL_WRITE_DELAY_MS);
}

function writeUrl() {
  const state = { ...app.state(), camera: viewer.getCamera(), display };
  const search = encodeState(state, new URLSearchParams(location.search));
  history.replaceState(null, '', `${location.pathname}?${search}`);
  try {
    localStorage.setItem(STORAGE_KEY, search);
  } catch {
    // storage full or disabled: the URL still holds the scene
  }
}

async function copyLink() {
  clearTimeout(urlTimer);
  urlTimer = null;
  writeUrl();
  const link = location.href;
  try {
    await navigator.clipboard.writeText(link);
    panel.showShareNote('Link copied: it opens this view.', link);
  } catch {
    panel.showShareNote('Copy this link (the browser did not allow copying):', link);
  }
}

// ---- export -----------------------------------------------------------------------------------

async function exportAs(format) {
  try {
    if (format === 'png') {
      download(await viewer.toPng(), 'isomesh.png');
      panel.showShareNote('Saved isomesh.png.');
      return;
    }
    const surfaces = app.exportSurfaces();
    if (surfaces.length === 0) {
      panel.showShareNote('Nothing to export: no visible surface has triangles.');
      return;
    }
    const triangles = surfaces.reduce((n, s) => n + s.indices.length / 3, 0);
    if (format === 'glb') download(await toGlb(surfaces), 'isomesh.glb', 'model/gltf-binary');
    else if (format === 'stl') download(toStl(surfaces), 'isomesh.stl', 'model/stl');
    else download(toObj(surfaces), 'isomesh.obj', 'text/plain');
    panel.showShareNote(`Saved isomesh.${format}: ${triangles} triangles in ${surfaces.length} surface${surfaces.length > 1 ? 's' : ''}.`);
  } catch (error) {
    panel.showShareNote(`Export failed: ${error.message}`);
    console.warn('isomesh export:', error);
  }
}

// ---- status -----------------------------------------------------------------------------------

function showStatus() {
  const s = app.snapshot();
  const part = (text, extra = false) => Object.assign(document.createElement('span'), { textContent: `${text} · `, className: extra ? 'extra' : '' });
  const parts = [part(`${s.triangles} triangles`)];
  if (s.errorMax !== null && s.triangles > 0) parts.push(part(`max error ${s.errorMax.toPrecision(3)}`, true));
  parts.push(part(`${formatBytes(s.bytesReceived)} received`, true));
  if (s.firstMeshMs !== null) parts.push(part(`first mesh ${s.firstMeshMs.toFixed(1)} ms`, true));
  const state = document.createElement('span');
  state.className = `state-${s.status}`;
  state.textContent = `${STATUS_WORDS[s.status] ?? s.status}${s.detail ? ` (${s.detail})` : ''}`;
  statusLine.replaceChildren(...parts, state);
}

function formatBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KB`;
  return `${(n / 1024 / 1024).toFixed(2)} MB`;
}

/** A sum over the held meshes' positions: changes whenever a surface does (for tests). */
function meshSignature() {
  let sum = 0;
  let triangles = 0;
  for (const row of app.rows) {
    const slots = row.surface.session?.mesh.slots;
    if (!slots) continue;
    triangles += slots.count;
    const end = 9 * slots.count;
    for (let i = 0; i < end; ++i) sum += Math.abs(slots.positions[i]) * ((i % 9) + 1);
  }
  return { triangles, sum };
}

// ---- start ------------------------------------------------------------------------------------

function followColorScheme() {
  const dark = matchMedia('(prefers-color-scheme: dark)');
  const apply = () => viewer.setTheme(dark.matches ? DARK_THEME : LIGHT_THEME);
  dark.addEventListener('change', apply);
  apply();
}

async function main() {
  followColorScheme();
  panel.setBox(initial.box);
  viewer.setBox(initial.box, { frame: !initial.camera });
  if (initial.camera) viewer.setCamera(initial.camera);
  setDisplay({});
  if (initial.constraints) panel.setConstraints(initial.constraints);
  const decoder = await loadDracoDecoder({ locateFile: () => dracoWasmUrl });
  app = new App({ url, decoder, viewer, objects, sliders, panel, state: initial });
  sliders.setNames(app.sliderNames(), app.parameters, initial.sliders ?? {});
  pump = new FramePump({
    drain: (deadline) => app.client?.drainFrames(deadline),
    pending: () => app.client?.pendingFrames ?? 0,
  });
  viewer.hooks.beforeRender = () => pump.onAnimationFrame();
  document.addEventListener('visibilitychange', () => pump.visibilityChanged());
  pump.visibilityChanged();
  viewer.onCameraChange = () => sceneChanged();
  app.onStateChange = () => sceneChanged();
  app.onStatus = () => showStatus();
  bindShortcuts($('#help'), $('#help-keys'), {
    resetView: () => viewer.frameBox(),
    togglePanel: () => showPanel(document.body.classList.contains('panel-hidden')),
    addSurface: () => app.addSurface({}, { focus: true }),
    toggleWireframe: () => setDisplay({ wireframe: !display.wireframe }),
    toggleAxes: () => toggleShown('axes'),
    toggleGrid: () => toggleShown('grid'),
    nextColorMode: () => setDisplay({ colorMode: COLOR_MODES[(COLOR_MODES.indexOf(display.colorMode) + 1) % COLOR_MODES.length] }),
    togglePause: () => app.togglePause(),
  });
  window.isomesh = {
    get status() {
      return app.status;
    },
    snapshot: () => app.snapshot(),
    meshSignature,
    journal: () => app.rows.map((r) => [...r.surface.journal]),
    renderedFrames: () => viewer.frames,
    longestFrameSliceMs: () => pump.longestSliceMs,
    /** Per surface: GPU buffers made anew, and floats uploaded in place since the start. */
    geometryStats: () => [...viewer.surfaces].map(({ slotGeometry: g }) => ({ rebinds: g.rebinds, rangeFloats: g.totalRangeFloats })),
    app,
    viewer,
    pump,
  };
  sceneChanged();
  await app.start();
}

function toggleShown(key) {
  const show = display.show.includes(key) ? display.show.filter((k) => k !== key) : [...display.show, key];
  setDisplay({ show });
}

main().catch((error) => {
  statusLine.textContent = `failed to start: ${error.message}`;
  console.error(error);
});

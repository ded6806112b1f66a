// The isomesh browser viewer: wires the panel, the 3D view and the session together, and exposes
// the viewer's state as `window.isomesh` (read by the browser test and handy in the console).
//
// URL options: ?server=ws://host:port/ws (default: /ws of the page's own server),
// ?expr=EQUATION for the first equation (default: the first gallery example).

import { loadDracoDecoder } from 'isomesh-client';
import dracoWasmUrl from 'draco3d/draco_decoder.wasm?url';

import { App } from './app.js';
import { GALLERY } from './gallery.js';
import { Panel } from './panel.js';
import { Viewer } from './viewer.js';

const query = new URLSearchParams(location.search);
const defaultUrl = `${location.protocol === 'https:' ? 'wss:' : 'ws:'}//${location.host}/ws`;
const url = query.get('server') ?? defaultUrl;
const first = query.get('expr') ? { expression: query.get('expr'), box: [-3, 3, -3, 3, -3, 3] } : GALLERY[0];

const FRAME_BUDGET_MS = 8;
const statusLine = document.querySelector('#status');
let app = null;

const viewer = new Viewer(document.querySelector('#canvas-host'));
const panel = new Panel({
  onEquation: (text) => app?.setEquation(text),
  onParameter: (name, value) => app?.setParameter(name, value),
  onBudget: (triangles) => app?.setConstraints({ triangles }),
  onMaxError: (value) => app?.setConstraints({ max_error: value }),
  onErrorMeasure: (name) => app?.setConstraints({ error_measure: name }),
  onBox: (box) => app?.setBox(box),
  onGallery: (example) => app?.showExample(example),
  onWireframe: (on) => viewer.setWireframe(on),
  onShowBox: (on) => viewer.setBoxVisible(on),
  onResetView: () => viewer.frameBox(),
  onPause: () => app?.togglePause(),
});
panel.setEquation(first.expression);
viewer.setBox(first.box, { frame: true });

function showStatus() {
  const s = app.snapshot();
  const parts = [];
  if (s.session) {
    parts.push(`${s.triangles.toLocaleString('en-US')} triangles`);
    if (s.errorMax !== null) parts.push(`error ${s.errorMax.toPrecision(3)}`);
    parts.push(`${formatBytes(s.bytesReceived)} received`);
    if (s.firstMeshMs !== null) parts.push(`first mesh ${s.firstMeshMs.toFixed(1)} ms`);
  }
  const state = document.createElement('span');
  state.className = `state-${s.status}`;
  state.textContent = s.detail ? `${s.status} (${s.detail})` : s.status;
  statusLine.replaceChildren(parts.join(' · ') + (parts.length ? ' · ' : ''), state);
}

function formatBytes(n) {
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KB`;
  return `${(n / 1024 / 1024).toFixed(2)} MB`;
}

/** A sum over the live mesh's positions: changes whenever the surface does (for tests). */
function meshSignature() {
  const slots = app?.session?.mesh.slots;
  if (!slots) return null;
  let sum = 0;
  const end = 9 * slots.count;
  for (let i = 0; i < end; ++i) sum += Math.abs(slots.positions[i]) * ((i % 9) + 1);
  return { triangles: slots.count, sum };
}

let statusQueued = false;
async function main() {
  const decoder = await loadDracoDecoder({ locateFile: () => dracoWasmUrl });
  app = new App({ panel, viewer, url, decoder, initial: first });
  // 8 ms of frame decoding per animation frame keeps orbiting smooth while refinement streams;
  // a hidden page gets no animation frames, so a timer drains the queue there.
  let lastDrain = performance.now();
  viewer.hooks.beforeRender = () => {
    lastDrain = performance.now();
    return app.drainFrames(FRAME_BUDGET_MS);
  };
  setInterval(() => {
    if (performance.now() - lastDrain > 200) app.drainFrames(Infinity);
  }, 250);
  app.onStatus = () => {
    // At most one status line update per animation frame, however many frames arrive.
    if (statusQueued) return;
    statusQueued = true;
    requestAnimationFrame(() => {
      statusQueued = false;
      showStatus();
    });
  };
  window.isomesh = {
    get status() {
      return app.status;
    },
    snapshot: () => app.snapshot(),
    meshSignature,
    journal: () => [...app.journal],
    renderedFrames: () => viewer.frames,
    app,
    viewer,
  };
  await app.start();
}

main().catch((error) => {
  statusLine.textContent = `failed to start: ${error.message}`;
  console.error(error);
});

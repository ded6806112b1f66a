// A slider drag over the wire (not part of the test command): one session at a triangle budget,
// converged, then `update`s of a parameter sent at a fixed rate in real time (30 a second by
// default), as a user dragging a slider does, then the wait for convergence after the last. The
// client is the client library (clients/js) speaking protocol version 2, decoding and applying
// every frame; the server is a real isomesh-server on a free loopback port.
//
//   (cd tests/server/node && npm ci) && node bench/slider.mjs [--surface sphere|gyroid|torus|all]
//       [--updates N] [--rate HZ] [--triangles N] [--threads N] [--verbose]
//
// Per update (a function version; --verbose prints the table): the bytes of its frames (every
// binary payload whose header names that version) and of the text messages naming it; the
// vertices it moved (distinct ids of the moved vertices of its decoded deltas); bytes per moved
// vertex; the latency from sending the update to the first frame whose version is this one or
// newer, received (its bytes read from the socket) and applied (decoded and applied by the client
// library: what a viewer can draw). A server may skip a version that a newer one superseded
// before it was shown: such versions have no frames of their own, and are counted. Then: p50 and
// p99 of both latencies, the median bytes per moved vertex, the total bytes, the time from the
// last update to its `converged`, and the load average (the machine is shared: latencies are
// wall-clock times).

import { loadavg } from 'node:os';
import { performance } from 'node:perf_hooks';

import { connect } from '../clients/js/src/index.js';
import { decoder, startServer, WebSocket } from '../tests/server/node/harness.js';

const arg = (name, fallback) => (process.argv.includes(name) ? process.argv[process.argv.indexOf(name) + 1] : fallback);
const verbose = process.argv.includes('--verbose');

const SURFACES = {
  sphere: { expression: 'x^2+y^2+z^2=a', from: 2, to: 6 },
  gyroid: { expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=a', from: 0, to: 0.5 },
  torus: { expression: '(sqrt(x^2+y^2)-2)^2+z^2=a', from: 0.2, to: 0.8 },
};
const BOX = [-3, 3, -3, 3, -3, 3];

/** The function version a frame names (offset 48 in every frame layout of both versions). */
function frameVersion(bytes) {
  return new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength).getUint32(48, true);
}

/**
 * A WebSocket of the `ws` package that reports every payload it receives to `tap(data, at)`
 * before the client library handles it.
 */
function tappedWebSocket(tap) {
  return class extends WebSocket {
    set onmessage(handler) {
      super.onmessage = (event) => {
        tap(event.data, performance.now());
        handler(event);
      };
    }

    get onmessage() {
      return super.onmessage;
    }
  };
}

/** Per function version: bytes, moved vertex ids, the first frame's arrival. */
class VersionLedger {
  constructor() {
    this.versions = new Map();
  }

  of(version) {
    if (!this.versions.has(version)) {
      this.versions.set(version, { bytes: 0, frames: 0, texts: 0, moved: new Set(), firstFrameAt: null, firstReceivedAt: null, applyMs: 0 });
    }
    return this.versions.get(version);
  }

  /** A WebSocket payload: binary frames count for the version in their header, texts for theirs. */
  payload(data, at) {
    if (typeof data === 'string') {
      const version = JSON.parse(data).version;
      if (version !== undefined) {
        const entry = this.of(version);
        entry.bytes += Buffer.byteLength(data);
        ++entry.texts;
      }
      return;
    }
    const bytes = new Uint8Array(data);
    const entry = this.of(frameVersion(bytes));
    entry.firstReceivedAt ??= at;
    entry.bytes += bytes.length;
    ++entry.frames;
  }

  /** The time the library took to decode and apply a frame of `version`. */
  applyTime(version, ms) {
    this.of(version).applyMs += ms;
  }

  /** A frame the library applied. */
  applied(frame, at) {
    const entry = this.of(frame.header.functionVersion);
    entry.firstFrameAt ??= at;
    for (const id of frame.moved ?? []) entry.moved.add(id);
  }
}

/** Records the time the session's mesh takes to decode (version 2) and apply each frame. */
function timeApplies(mesh, ledger) {
  const apply = mesh.apply.bind(mesh);
  mesh.apply = (frame) => {
    const start = performance.now();
    const outcome = apply(frame);
    ledger.applyTime(frame.header.functionVersion, performance.now() - start);
    return outcome;
  };
}

const quantile = (values, q) => {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
};
const median = (values) => quantile(values, 0.5);
const sleepUntil = (t) => new Promise((resolve) => setTimeout(resolve, Math.max(0, t - performance.now())));

/** Waits until the session holds the converged mesh of `version`; resolves with the time. */
async function convergedAt(session, version, timeoutMs) {
  const end = performance.now() + timeoutMs;
  while (!(session.converged && session.state.version === version)) {
    if (performance.now() > end) throw new Error(`no convergence of version ${version} within ${timeoutMs} ms`);
    await new Promise((resolve) => setTimeout(resolve, 1));
  }
  return performance.now();
}

async function drag(server, name, surface, settings) {
  const ledger = new VersionLedger();
  const client = await connect(server.wsUrl, {
    WebSocket: tappedWebSocket((data, at) => ledger.payload(data, at)),
    decoder: await decoder(),
    protocolVersion: 2,
    route: null,
    reconnect: false,
  });
  try {
    const session = await client.create({
      expression: surface.expression,
      parameters: { a: surface.from },
      box: BOX,
      constraints: { triangles: settings.triangles },
    });
    for (const kind of ['keyframe', 'delta']) session.on(kind, (frame) => ledger.applied(frame, performance.now()));
    timeApplies(session.mesh, ledger);
    await convergedAt(session, 1, 60000);
    const first = session.state.version;
    const sent = [];
    const start = performance.now();
    for (let i = 1; i <= settings.updates; ++i) {
      await sleepUntil(start + ((i - 1) * 1000) / settings.rate);
      const a = surface.from + ((surface.to - surface.from) * i) / settings.updates;
      sent.push({ version: first + i, a, at: performance.now() });
      session.update({ parameters: { a } }).catch((error) => console.error(`update ${i}: ${error.message}`));
    }
    const last = sent[sent.length - 1];
    const convergedTime = (await convergedAt(session, last.version, 60000)) - last.at;
    return report(name, ledger, sent, convergedTime, session);
  } finally {
    client.close();
  }
}

/** The earliest `field` time of the versions from `version` on (null when none has one). */
function firstFrom(ledger, version, field) {
  let first = null;
  for (const [v, e] of ledger.versions) {
    if (v >= version && e[field] !== null && (first === null || e[field] < first)) first = e[field];
  }
  return first;
}

function row(ledger, { version, a, at }) {
  const entry = ledger.of(version);
  const applied = firstFrom(ledger, version, 'firstFrameAt');
  const received = firstFrom(ledger, version, 'firstReceivedAt');
  return {
    version,
    a,
    bytes: entry.bytes,
    frames: entry.frames,
    moved: entry.moved.size,
    applyMs: entry.applyMs,
    latency: applied === null ? null : applied - at,
    received: received === null ? null : received - at,
    own: entry.firstFrameAt !== null,
  };
}

function printRows(rows) {
  const cells = ['version', 'a', 'frames', 'bytes', 'moved', 'B/moved', 'received', 'applied', 'apply ms'];
  const widths = [7, 7, 6, 8, 6, 7, 8, 8, 8];
  const line = (values) => `  ${values.map((v, i) => String(v).padStart(widths[i])).join(' ')}`;
  console.log(line(cells));
  const ms = (x, own) => (x === null ? '-' : `${x.toFixed(1)}${own ? '' : '*'}`);
  for (const r of rows) {
    const perMoved = r.moved > 0 ? (r.bytes / r.moved).toFixed(2) : '-';
    console.log(line([r.version, r.a.toFixed(3), r.frames, r.bytes, r.moved, perMoved, ms(r.received, r.own), ms(r.latency, r.own), r.applyMs.toFixed(1)]));
  }
  console.log('  (ms from sending the update; * the first frame was of a newer version: this one was superseded;');
  console.log('   apply ms: the time the client library took to decode and apply the version\'s frames)');
}

function report(name, ledger, sent, convergedTime, session) {
  const rows = sent.map((update) => row(ledger, update));
  if (verbose) printRows(rows);
  const latencies = rows.filter((r) => r.latency !== null).map((r) => r.latency);
  const received = rows.filter((r) => r.received !== null).map((r) => r.received);
  const perMoved = rows.filter((r) => r.moved > 0).map((r) => r.bytes / r.moved);
  const applyMs = rows.filter((r) => r.moved > 0).map((r) => r.applyMs);
  const total = rows.reduce((sum, r) => sum + r.bytes, 0);
  const skipped = rows.filter((r) => !r.own).length;
  const fixed = (x, digits = 1) => (x === undefined ? '-' : x.toFixed(digits));
  console.log(
    `${name.padEnd(7)} ${rows.length} updates, ${session.lastConverged.triangles} triangles: ` +
      `update to frame applied p50 ${fixed(median(latencies))} ms, p99 ${fixed(quantile(latencies, 0.99))} ms ` +
      `(received p50 ${fixed(median(received))}, p99 ${fixed(quantile(received, 0.99))}); ` +
      `client decode and apply p50 ${fixed(median(applyMs))} ms; ` +
      `bytes per moved vertex median ${fixed(median(perMoved), 2)} ` +
      `(${perMoved.length} versions with moves, ${skipped} superseded unshown); ` +
      `total ${total} bytes; last update to converged ${convergedTime.toFixed(0)} ms`,
  );
}

const settings = {
  updates: Number(arg('--updates', '60')),
  rate: Number(arg('--rate', '30')),
  triangles: Number(arg('--triangles', '20000')),
};
const which = arg('--surface', 'all');
const names = which === 'all' ? Object.keys(SURFACES) : [which];
const server = await startServer(['--threads', arg('--threads', '2')]);
try {
  console.log(`slider drag: ${settings.updates} updates at ${settings.rate} a second, budget ${settings.triangles}, protocol version 2`);
  const load = () => loadavg().map((x) => x.toFixed(2)).join(' ');
  console.log(`load average before: ${load()}`);
  for (const name of names) await drag(server, name, SURFACES[name], settings);
  console.log(`load average after: ${load()}`);
} finally {
  await server.stop();
}

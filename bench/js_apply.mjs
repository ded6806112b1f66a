// Applying frames in the JavaScript client library (clients/js), protocol version 1 against
// version 2, in the same run (not part of the test command). A real isomesh-server streams the same
// sessions to two connections of the library, one speaking each version, and every binary frame
// they receive is recorded; the recordings are then replayed offline into fresh SessionMesh
// objects many times (after a warm-up), v1 and v2 in turn, timing each stage:
//
//   decodeFrame  header, id varints and checks (Draco's part excluded)
//   draco        the Draco payloads (every v1 frame; v2 keyframes only)
//   v2 decode    version-2 delta bodies decoded against the held mesh (inside SessionMesh.apply)
//   apply        the rest of SessionMesh.apply: slot table, vertex table, held mesh
//
//   (cd tests/server/node && npm ci) && node bench/js_apply.mjs [--reps N] [--warmup N]
//       [--threads N] [--only NAME] [--save DIR | --load DIR]
//
// It starts build/bin/isomesh-server (or $ISOMESH_BIN_DIR's) itself. Times are medians over the
// repetitions; "µs/tri" is the time per triangle the frames add, and the last line of each
// scenario is the ratio v2 / v1 (the target: at most 1). Scenarios: the sphere at 5,000 and
// 50,000 triangles, the gyroid at 100,000, and a slider (x^2+y^2+z^2=a at 20,000, a from 2 to 6 in
// 30 updates a second apart by 33 ms; only the frames after the first update are timed: the mesh
// they apply to is built untimed first). --save writes the recordings (DIR/NAME-vN/NNNN.bin);
// --load replays such recordings instead of starting a server (to compare two versions of the
// library on the same frames).

import { mkdirSync, readFileSync, readdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { performance } from 'node:perf_hooks';

import { connect, decodeFrame, Outcome, SessionMesh } from '../clients/js/src/index.js';
import { decoder, startServer, WebSocket } from '../tests/server/node/harness.js';

const arg = (name, fallback) => (process.argv.includes(name) ? process.argv[process.argv.indexOf(name) + 1] : fallback);
const reps = Number(arg('--reps', '15'));
const warmup = Number(arg('--warmup', '5'));
const threads = arg('--threads', '2');
const only = arg('--only', null);
const saveDir = arg('--save', null);
const loadDir = arg('--load', null);

const SPHERE = { expression: 'x^2+y^2+z^2=4', box: [-3, 3, -3, 3, -3, 3] };
const SCENARIOS = [
  { name: 'sphere-5k', ...SPHERE, triangles: 5000 },
  { name: 'sphere-50k', ...SPHERE, triangles: 50000 },
  { name: 'gyroid-100k', expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', box: [-5, 5, -5, 5, -5, 5], triangles: 100000 },
  { name: 'slider-20k', expression: 'x^2+y^2+z^2=a', parameters: { a: 2 }, box: [-3, 3, -3, 3, -3, 3], triangles: 20000, slider: { from: 2, to: 6, steps: 30, everyMs: 33 } },
];

/** A `ws` WebSocket class that copies every binary message it receives into `frames`. */
function recordingSocket(frames) {
  return class RecordingWebSocket extends WebSocket {
    constructor(...args) {
      super(...args);
      this.on('message', (data, isBinary) => {
        if (!isBinary) return;
        const parts = Array.isArray(data) ? data : [data];
        frames.push(new Uint8Array(Buffer.concat(parts.map((p) => Buffer.from(p)))));
      });
    }
  };
}

async function untilConverged(session, what) {
  const end = Date.now() + 180000;
  while (!session.converged) {
    if (Date.now() > end) throw new Error(`${what}: no convergence within 180 s`);
    await new Promise((resolve) => setTimeout(resolve, 5));
  }
}

/**
 * The binary frames of one session of `scenario` on a connection speaking `version`, from create
 * to convergence (for a slider: to convergence after the last update); `timedFrom`: the index of
 * the first frame timed.
 */
async function record(server, scenario, version) {
  const frames = [];
  const client = await connect(server.wsUrl, {
    WebSocket: recordingSocket(frames), decoder: await decoder(), protocolVersion: version, route: null, reconnect: false,
  });
  try {
    const { expression, parameters, box, triangles } = scenario;
    const session = await client.create({ expression, parameters, box, constraints: { triangles } });
    await untilConverged(session, scenario.name);
    let timedFrom = 0;
    if (scenario.slider) {
      timedFrom = frames.length;
      const { from, to, steps, everyMs } = scenario.slider;
      const updates = [];
      for (let i = 1; i <= steps; ++i) {
        updates.push(session.update({ parameters: { a: from + ((to - from) * i) / steps } }));
        await new Promise((resolve) => setTimeout(resolve, everyMs));
      }
      await Promise.all(updates);
      await untilConverged(session, scenario.name);
    }
    if (session.stats.resyncs > 0) throw new Error(`${scenario.name} v${version}: the client had to resync`);
    return { version, frames, timedFrom, finalTriangles: session.lastConverged.triangles };
  } finally {
    client.close();
  }
}

/** Draco's decoder with the time spent in it counted. */
function timedDecoder(inner, stages) {
  return {
    decode(...args) {
      const start = performance.now();
      try {
        return inner.decode(...args);
      } finally {
        stages.draco += performance.now() - start;
      }
    },
  };
}

/** Applies a recording to a fresh SessionMesh; returns the stage times (ms) of the timed frames. */
function replay(recording, meshDecoder) {
  const stages = { decodeFrame: 0, draco: 0, decodeV2: 0, apply: 0, total: 0, added: 0 };
  const untimed = { decodeFrame: 0, draco: 0 };
  const mesh = new SessionMesh({ timing: true });
  const timed = timedDecoder(meshDecoder, stages);
  const quiet = timedDecoder(meshDecoder, untimed);
  recording.frames.forEach((bytes, i) => {
    const counted = i >= recording.timedFrom;
    const t0 = performance.now();
    const frame = decodeFrame(bytes, counted ? timed : quiet);
    const t1 = performance.now();
    const before = mesh.timing.decodeV2Ms;
    const outcome = mesh.apply(frame);
    const t2 = performance.now();
    if (outcome !== Outcome.applied) throw new Error(`frame ${i} of v${recording.version}: ${outcome} ${frame.error?.message ?? ''}`);
    if (!counted) return;
    const decodeV2 = mesh.timing.decodeV2Ms - before;
    stages.decodeFrame += t1 - t0;
    stages.decodeV2 += decodeV2;
    stages.apply += t2 - t1 - decodeV2;
    stages.total += t2 - t0;
    stages.added += frame.triangleIds.length;
  });
  stages.decodeFrame -= stages.draco;
  if (mesh.triangleCount !== recording.finalTriangles) {
    throw new Error(`v${recording.version}: ${mesh.triangleCount} triangles applied, the server converged at ${recording.finalTriangles}`);
  }
  return stages;
}

const median = (values) => [...values].sort((a, b) => a - b)[Math.floor(values.length / 2)];

/** Replays both recordings in turn, `warmup` then `reps` times; the median of every stage. */
function measure(recordings, meshDecoder) {
  const runs = recordings.map(() => []);
  for (let rep = 0; rep < warmup + reps; ++rep) {
    recordings.forEach((recording, k) => {
      const stages = replay(recording, meshDecoder);
      if (rep >= warmup) runs[k].push(stages);
    });
  }
  return runs.map((list) => Object.fromEntries(Object.keys(list[0]).map((key) => [key, median(list.map((s) => s[key]))])));
}

const ms = (x) => x.toFixed(2).padStart(9);

function printScenario(name, recordings, results) {
  recordings.forEach((recording, k) => {
    const r = results[k];
    const frames = recording.frames.length - recording.timedFrom;
    const perTriangle = r.added > 0 ? ((1000 * r.total) / r.added).toFixed(3) : '-';
    console.log(
      `${name.padEnd(12)} v${recording.version} ${String(frames).padStart(6)} ${String(r.added).padStart(8)} ${ms(r.total)} ` +
        `${perTriangle.padStart(8)} ${ms(r.decodeFrame)} ${ms(r.draco)} ${ms(r.decodeV2)} ${ms(r.apply)}`,
    );
  });
  const [v1, v2] = results;
  const perTriangle = v1.added > 0 && v2.added > 0 ? ((v2.total / v2.added) / (v1.total / v1.added)).toFixed(2) : '-';
  console.log(`${name.padEnd(12)} v2/v1: total ${(v2.total / v1.total).toFixed(2)}, per added triangle ${perTriangle}`);
}

function save(name, recording) {
  const dir = join(saveDir, `${name}-v${recording.version}`);
  mkdirSync(dir, { recursive: true });
  recording.frames.forEach((bytes, i) => writeFileSync(join(dir, `${String(i).padStart(4, '0')}.bin`), bytes));
  writeFileSync(join(dir, 'recording.json'), JSON.stringify({ timedFrom: recording.timedFrom, finalTriangles: recording.finalTriangles }));
}

function load(name, version) {
  const dir = join(loadDir, `${name}-v${version}`);
  const frames = readdirSync(dir).filter((f) => f.endsWith('.bin')).sort().map((f) => new Uint8Array(readFileSync(join(dir, f))));
  return { version, frames, ...JSON.parse(readFileSync(join(dir, 'recording.json'), 'utf8')) };
}

/** Both recordings of every scenario chosen: made by a server now, or loaded. */
async function recordAll(scenarios) {
  if (loadDir) return scenarios.map(({ name }) => ({ name, recordings: [load(name, 1), load(name, 2)] }));
  const server = await startServer(['--threads', threads]);
  const recorded = [];
  try {
    for (const scenario of scenarios) {
      const recordings = [await record(server, scenario, 1), await record(server, scenario, 2)];
      if (saveDir) recordings.forEach((recording) => save(scenario.name, recording));
      recorded.push({ name: scenario.name, recordings });
    }
  } finally {
    await server.stop();
  }
  return recorded;
}

const recorded = await recordAll(SCENARIOS.filter((s) => !only || s.name === only));
const meshDecoder = await decoder();
console.log(`replaying recorded frames: median of ${reps} runs after ${warmup} warm-up runs, v1 and v2 in turn (times in ms)`);
console.log(`${'scenario'.padEnd(12)} ver frames    added     total   µs/tri decodeFrame   draco  v2 decode    apply`);
for (const { name, recordings } of recorded) printScenario(name, recordings, measure(recordings, meshDecoder));

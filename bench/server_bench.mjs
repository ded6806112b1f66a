// Benchmark of isomesh-server over loopback (not part of the test command):
//   1. time from sending `create` to the first keyframe decoded and applied by the client, for the
//      thesis's sphere and the gallery (the thesis: 9 ms to a first visible mesh inside its app;
//      our aim: under 5 ms over the network), beside a `ping` round trip as the baseline of the
//      same connection;
//   2. bytes per added triangle over a full refinement (frames' bytes / triangles they add);
//   3. frame latency with 100 concurrent sessions refining and following a slider, beside the same
//      latency with one session: end to end (the frame's server timestamp, taken before encoding,
//      to the client having decoded and applied it) and on the server (made to written).
//
//   (cd tests/server/node && npm ci) && node bench/server_bench.mjs [--threads N] [--parts 1,2,3]
//
// It starts build/bin/isomesh-server (or $ISOMESH_BIN_DIR's) itself.

import { connect } from '../clients/js/src/index.js';
import { converged, decoder, startServer, WebSocket } from '../tests/server/node/harness.js';

/**
 * A connection of the client library, as a viewer has: the tests' client (harness.js) checks
 * every frame's validity in JavaScript before the frame's listeners run, milliseconds that are
 * not the server's (the gyroid's first keyframe: 16 ms with the check).
 */
async function client(server) {
  return connect(server.wsUrl, { decoder: await decoder(), WebSocket, route: null, reconnect: false });
}

const parts = process.argv.includes('--parts') ? process.argv[process.argv.indexOf('--parts') + 1].split(',') : ['1', '2', '3'];
const threads = process.argv.includes('--threads') ? process.argv[process.argv.indexOf('--threads') + 1] : '2';

const SURFACES = [
  { name: 'sphere |r|=3 (thesis)', expression: 'sqrt(x^2+y^2+z^2)=3', box: [-5, 5, -5, 5, -5, 5] },
  { name: 'wobbly sphere', expression: 'x^2+y^2+z^2+2cos(2x)=5', box: [-3, 3, -3, 3, -3, 3] },
  { name: 'torus', expression: '(sqrt(x^2+y^2)-1.8)^2+z^2=0.5', box: [-3, 3, -3, 3, -3, 3] },
  { name: 'tanglecube', expression: 'x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0', box: [-3, 3, -3, 3, -3, 3] },
  { name: 'oblate spheroid (thesis)', expression: '10x^2+y^2+z^2=20', box: [-5, 5, -5, 5, -5, 5] },
  { name: 'genus 2', expression: '((x-1)^2+y^2-1)((x+1)^2+y^2-1)-0.3+z^2=0', box: [-3, 3, -3, 3, -3, 3] },
  { name: 'gyroid', expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', box: [-6, 6, -6, 6, -6, 6] },
  { name: 'heart', expression: '(x^2+2.25y^2+z^2-1)^3-x^2z^3-0.1125y^2z^3=0', box: [-1.5, 1.5, -1.5, 1.5, -1.5, 1.5] },
  { name: 'blobby cube (thesis)', expression: 'sqrt(x^2+y^2+z^2)+2cos(2x)+2cos(2y)+2cos(2z)=20', box: [-28, 28, -28, 28, -28, 28] },
];

function percentile(values, p) {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}

const fmt = (x, digits = 2) => x.toFixed(digits);

async function firstKeyframe(server) {
  console.log('\n1. create -> first keyframe decoded (ms), 30 runs each; baseline: ping round trip');
  const connection = await client(server);
  const pings = [];
  for (let i = 0; i < 50; ++i) pings.push((await connection.ping()).rttMs);
  console.log(`   ping round trip: median ${fmt(percentile(pings, 0.5), 3)} ms`);
  for (const surface of SURFACES) {
    const times = [];
    let triangles = 0;
    for (let run = 0; run < 30; ++run) {
      const started = performance.now();
      const session = await connection.create({
        expression: surface.expression,
        box: surface.box,
        constraints: { triangles: 20000 }, // the default budget: the first keyframe is the first mesh
      });
      if (!session.mesh.synchronized) await session.once('keyframe');
      times.push(performance.now() - started);
      triangles = session.mesh.triangleCount;
      await connection.request('close', { session: session.id });
    }
    console.log(
      `   ${surface.name.padEnd(26)} ${String(triangles).padStart(6)} triangles: median ${fmt(percentile(times, 0.5))}` +
        `  p90 ${fmt(percentile(times, 0.9))}  (${fmt(percentile(times, 0.5) / percentile(pings, 0.5), 1)}x ping)`,
    );
  }
  connection.close();
}

async function bytesPerTriangle(server) {
  console.log('\n2. bytes per added triangle over a full refinement (50,000 triangles)');
  const connection = await client(server);
  for (const surface of SURFACES) {
    const session = await connection.create({ expression: surface.expression, box: surface.box, constraints: { triangles: 50000 } });
    let added = 0;
    let frames = 0;
    const count = (frame) => {
      added += frame.header.triangleCount;
      ++frames;
    };
    session.on('keyframe', count);
    session.on('delta', count);
    await converged(session, 120000);
    const bytes = session.stats.bytes;
    console.log(
      `   ${surface.name.padEnd(26)} ${session.stats.frames} frames, ${added} triangles added, ` +
        `${fmt(bytes / Math.max(added, 1))} bytes/triangle (raw float32 positions+normals: 36)`,
    );
    await connection.request('close', { session: session.id });
  }
  connection.close();
}

async function latencyUnderLoad(server, sessionCount) {
  const connections = await Promise.all(Array.from({ length: 10 }, () => client(server)));
  const latencies = [];
  const sessions = [];
  for (let i = 0; i < sessionCount; ++i) {
    const connection = connections[i % connections.length];
    const session = await connection.create({
      expression: 'x^2+y^2+z^2+a*cos(2x)=5', // the wobbly sphere with its wobble on a slider
      parameters: { a: 2 },
      box: [-3, 3, -3, 3, -3, 3],
      constraints: { triangles: 2000 },
    });
    const record = (frame) => latencies.push(Date.now() - frame.header.timestampUs / 1000);
    session.on('keyframe', record);
    session.on('delta', record);
    sessions.push(session);
  }
  // Five seconds of slider moves on every session, 4 per second each.
  const end = Date.now() + 5000;
  let updates = 0;
  while (Date.now() < end) {
    await Promise.all(sessions.map((s, i) => s.update({ parameters: { a: 2 + 0.2 * Math.sin(updates + i) } })));
    ++updates;
    await new Promise((resolve) => setTimeout(resolve, 250));
  }
  await Promise.all(sessions.map((s) => converged(s, 120000)));
  const metrics = await server.metrics();
  for (const connection of connections) connection.close();
  return { latencies, updates, metrics };
}

/** The q-quantile of a Prometheus histogram (upper bound of the bucket it falls in), in ms. */
function histogramQuantile(metrics, name, q, since = new Map()) {
  const buckets = [];
  for (const [key, value] of metrics) {
    const match = new RegExp(`^${name}_bucket\\{le="([^"]+)"\\}$`).exec(key);
    if (match) buckets.push([Number(match[1]), value - (since.get(key) ?? 0)]);
  }
  buckets.sort((a, b) => a[0] - b[0]);
  const total = buckets[buckets.length - 1][1];
  const bucket = buckets.find(([, count]) => count >= q * total);
  return 1000 * bucket[0];
}

async function frameLatency(server) {
  console.log('\n3. frame latency, server timestamp -> client receipt (ms), slider moving for 5 s');
  console.log('   (client: frame made -> decoded and applied; server: frame made -> last byte written,');
  console.log('    from the isomesh_frame_latency_seconds histogram, as bucket upper bounds)');
  for (const count of [1, 100]) {
    const before = await server.metrics();
    const { latencies, updates, metrics } = await latencyUnderLoad(server, count);
    const server50 = histogramQuantile(metrics, 'isomesh_frame_latency_seconds', 0.5, before);
    const server99 = histogramQuantile(metrics, 'isomesh_frame_latency_seconds', 0.99, before);
    console.log(
      `   ${String(count).padStart(3)} wobbly spheres of 2,000 triangles, ${updates} slider steps each, ${latencies.length} frames:\n` +
        `       client median ${fmt(percentile(latencies, 0.5))}  p90 ${fmt(percentile(latencies, 0.9))}  p99 ${fmt(percentile(latencies, 0.99))}` +
        `   server median <= ${fmt(server50)}  p99 <= ${fmt(server99)}`,
    );
  }
}

const server = await startServer(['--threads', threads, '--orphan-timeout', '1', '--max-sessions-per-connection', '64']);
try {
  console.log(`isomesh-server on port ${server.port}, ${threads} worker threads`);
  if (parts.includes('1')) await firstKeyframe(server);
  if (parts.includes('2')) await bytesPerTriangle(server);
  if (parts.includes('3')) await frameLatency(server);
} finally {
  await server.stop();
}

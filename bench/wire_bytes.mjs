// Bytes on the wire (not part of the test command): every WebSocket payload byte a client receives
// for one session, from sending `create` to the `converged` message, per triangle of the final
// mesh, in protocol version 1 and version 2 over the same server, side by side. Also the bytes of
// the deltas after the last keyframe per triangle they added (net: final triangles minus the last
// keyframe's), and where they went (keyframes, deltas, control messages). The client is the client
// library (clients/js) with options.protocolVersion 1 or 2, decoding and applying every frame.
//
//   (cd tests/server/node && npm ci) && node bench/wire_bytes.mjs [--runs N] [--threads N]
//
// It starts build/bin/isomesh-server (or $ISOMESH_BIN_DIR's) itself. Surfaces: the sphere
// x^2+y^2+z^2=4 at budget 5,000 and the gallery's gyroid (t = 0, box ±6) at 100,000.

import { connect } from '../clients/js/src/index.js';
import { decoder, startServer, WebSocket } from '../tests/server/node/harness.js';

const arg = (name, fallback) => (process.argv.includes(name) ? process.argv[process.argv.indexOf(name) + 1] : fallback);
const runs = Number(arg('--runs', '3'));
const threads = arg('--threads', '2');

const SURFACES = [
  { name: 'sphere, budget 5,000', expression: 'x^2+y^2+z^2=4', box: [-3, 3, -3, 3, -3, 3], triangles: 5000 },
  { name: 'gyroid, budget 100,000', expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=t', parameters: { t: 0 }, box: [-6, 6, -6, 6, -6, 6], triangles: 100000 },
];

/**
 * One session on a fresh connection of the client library (clients/js) speaking `version`, every
 * frame decoded and applied; resolves with its byte counts once it converges.
 */
async function measure(server, surface, version) {
  const client = await connect(server.wsUrl, { WebSocket, decoder: await decoder(), protocolVersion: version, route: null, reconnect: false });
  try {
    const bytes = { keyframes: 0, deltas: 0, text: 0, deltasAfterKeyframe: 0, frames: 0, keyframeList: [] };
    let keyframeTriangles = 0;
    let counted = 0;
    const session = await client.create({ expression: surface.expression, parameters: surface.parameters, box: surface.box, constraints: { triangles: surface.triangles } });
    const frameBytes = () => {
      const n = session.stats.bytes - counted;
      counted = session.stats.bytes;
      ++bytes.frames;
      return n;
    };
    // Frames the library applied before create() resolved (a small first keyframe may arrive in
    // the same read as `created`): the first keyframe.
    if (session.stats.keyframes > 0) {
      const n = frameBytes();
      bytes.keyframes += n;
      keyframeTriangles = session.mesh.triangleCount;
      bytes.keyframeList.push(`${keyframeTriangles}:${n}`);
    }
    session.on('keyframe', (frame) => {
      if (frame.header.version !== version) throw new Error(`frame of version ${frame.header.version} on a version-${version} connection`);
      const n = frameBytes();
      bytes.keyframes += n;
      keyframeTriangles = frame.header.triangleCount;
      bytes.keyframeList.push(`${keyframeTriangles}:${n}`);
      bytes.deltasAfterKeyframe = 0;
    });
    session.on('delta', (frame) => {
      if (frame.header.version !== version) throw new Error(`frame of version ${frame.header.version} on a version-${version} connection`);
      const n = frameBytes();
      bytes.deltas += n;
      bytes.deltasAfterKeyframe += n;
    });
    const end = Date.now() + 120000;
    while (!session.converged) {
      if (Date.now() > end) throw new Error(`${surface.name}: no convergence within 120 s`);
      if (session.stats.resyncs > 0) throw new Error(`${surface.name}: the client had to resync`);
      await new Promise((resolve) => setTimeout(resolve, 5));
    }
    bytes.text = client.bytesReceived - session.stats.bytes;
    return { ...bytes, triangles: session.lastConverged.triangles, keyframeTriangles };
  } finally {
    client.close();
  }
}

const median = (values) => [...values].sort((a, b) => a - b)[Math.floor(values.length / 2)];
const fmt = (x) => x.toFixed(2);

const server = await startServer(['--threads', threads]);
try {
  console.log(`bytes received from create to converged, median of ${runs} runs (each run: v1 then v2, same server)`);
  for (const surface of SURFACES) {
    const results = { 1: [], 2: [] };
    for (let run = 0; run < runs; ++run) {
      for (const version of [1, 2]) results[version].push(await measure(server, surface, version));
    }
    const perFinal = {};
    for (const version of [1, 2]) {
      const r = results[version];
      const total = (x) => x.keyframes + x.deltas + x.text;
      perFinal[version] = median(r.map((x) => total(x) / x.triangles));
      const perAdded = median(r.map((x) => x.deltasAfterKeyframe / Math.max(1, x.triangles - x.keyframeTriangles)));
      const m = r[r.map((x) => total(x) / x.triangles).indexOf(perFinal[version])];
      console.log(
        `  ${surface.name.padEnd(24)} v${version}: ${fmt(perFinal[version])} bytes per final triangle ` +
          `(${m.triangles} triangles, ${total(m)} bytes: keyframes ${m.keyframes}, deltas ${m.deltas} in ${m.frames} frames, control ${m.text}); ` +
          `deltas after the last keyframe: ${fmt(perAdded)} bytes per added triangle`,
      );
      if (process.argv.includes('--verbose')) console.log(`    keyframes (triangles:bytes): ${m.keyframeList.join(' ')}`);
    }
    console.log(`  ${surface.name.padEnd(24)} v2 / v1 = ${fmt(perFinal[2] / perFinal[1])}`);
  }
} finally {
  await server.stop();
}

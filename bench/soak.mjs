// A bounded soak of isomesh-server's protections (issue 14), not part of the test command. Each
// part starts its own server (build/bin, or $ISOMESH_BIN_DIR) and prints its figures beside the
// target and a baseline measured in the same run:
//   1. region equations (the function is zero on a whole region): time to a coded outcome, the
//      server's resident growth, and the first-mesh time of a sphere created meanwhile on another
//      connection (baseline: the same sphere on an idle server);
//   2. 1,000 connections that create a session and vanish without a close frame: sessions created
//      and refused, resident memory at the start, at the peak, and once the sessions expired;
//   3. one connection cycling create/unsubscribe 64 times: sessions it holds, resident memory;
//   4. out of file descriptors (prlimit --nofile=64, 100 idle TCP connections): the server's CPU
//      over 5 s (baseline: the same server idle), /healthz, and warning lines logged;
//   5. memory per triangle: resident growth of converged gyroid sessions per triangle (what
//      server/resources.h's SessionMemory::kBytesPerTriangle rounds up), and what is left after
//      they close (periodic malloc_trim).
//
//   (cd tests/server/node && npm ci) && node bench/soak.mjs [part...]   (parts 1-5, default all)

import { readFileSync } from 'node:fs';
import net from 'node:net';

import { client, converged, rawSocket, startServer, until } from '../tests/server/node/harness.js';

const parts = process.argv.slice(2).map(Number);
const wanted = (n) => parts.length === 0 || parts.includes(n);
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
const mb = (kb) => `${(kb / 1024).toFixed(0)} MB`;
const verdict = (ok) => (ok ? 'meets the target' : 'MISSES the target');

/** User + system CPU seconds of a process so far (/proc/PID/stat). */
function cpuSeconds(pid) {
  const fields = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return (Number(fields[11]) + Number(fields[12])) / 100; // utime, stime in clock ticks
}

async function firstMeshMs(server) {
  const connection = await client(server);
  const started = performance.now();
  const session = await connection.create({ expression: 'x^2+y^2+z^2=1', box: [-2, 2, -2, 2, -2, 2], constraints: { triangles: 1000 } });
  if (!session.mesh.synchronized) await session.once('keyframe');
  const ms = performance.now() - started;
  connection.close();
  return ms;
}

async function regions() {
  console.log('\n1. region equations on [-2,2]^3 (target: coded outcome within 1 s, resident growth < 100 MB,');
  console.log('   a sphere elsewhere meshed within 100 ms); each cut off after 20 s');
  for (const expression of ['floor(x)=0', 'min(x,0)=0', 'max(x^2+y^2+z^2-1,0)=0', '0', 'x=x']) {
    const server = await startServer(['--eval-timeout-ms', '1000']);
    const idleSphere = await firstMeshMs(server);
    const before = server.status().rssKb;
    const raw = await rawSocket(server);
    const started = performance.now();
    raw.send({ v: 1, type: 'create', id: 1, expression, box: [-2, 2, -2, 2, -2, 2] });
    await sleep(50);
    const sphere = await firstMeshMs(server);
    let peak = before;
    let outcome = null;
    while (performance.now() - started < 20000 && !outcome) {
      peak = Math.max(peak, server.status().rssKb);
      const m = raw.messages.find((x) => x.type === 'error' || x.type === 'converged');
      if (m) outcome = { what: m.type === 'error' ? m.code : 'converged', ms: performance.now() - started };
      await sleep(20);
    }
    raw.socket.terminate();
    const ok = outcome && outcome.ms < 1000 && peak - before < 100 * 1024 && sphere < 100;
    console.log(
      `   ${expression.padEnd(24)} ${outcome ? `${outcome.what} after ${outcome.ms.toFixed(0)} ms` : 'no outcome in 20 s'};` +
        ` resident +${mb(peak - before)}; sphere meanwhile ${sphere.toFixed(1)} ms (idle server: ${idleSphere.toFixed(1)} ms): ${verdict(ok)}`,
    );
    const { code, signal } = await server.stop();
    if (code !== 0) console.log(`   (server exit ${code ?? signal}: the drain did not end it)`);
  }
}

async function disconnects() {
  console.log('\n2. 1,000 connections each creating a session, then vanishing (no close frame)');
  console.log('   (target: resident memory within 200 MB of the start once the sessions expired)');
  const server = await startServer(['--orphan-timeout', '3']);
  const start = server.status().rssKb;
  let created = 0;
  let refused = 0;
  let peak = start;
  for (let batch = 0; batch < 20; ++batch) {
    await Promise.all(
      Array.from({ length: 50 }, async () => {
        const raw = await rawSocket(server);
        raw.send({ v: 1, type: 'create', id: 1, expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', box: [-5, 5, -5, 5, -5, 5], constraints: { triangles: 20000 } });
        const reply = await raw.reply(1, 60000);
        if (reply.type === 'created') ++created;
        else ++refused;
        raw.socket._socket.destroy();
      }),
    );
    peak = Math.max(peak, server.status().rssKb);
  }
  const metrics = await server.metrics();
  await until(async () => (await server.metrics()).get('isomesh_sessions') === 0, { timeoutMs: 60000, what: 'sessions to expire' });
  await sleep(2000); // the housekeeper trims once a second
  const after = server.status().rssKb;
  console.log(
    `   ${created} created, ${refused} refused (server_busy: ${metrics.get('isomesh_sessions_refused_total{reason="sessions"}')} by count,` +
      ` ${metrics.get('isomesh_sessions_refused_total{reason="memory"}')} by memory); resident ${mb(start)} at the start, ${mb(peak)} at the peak,` +
      ` ${mb(after)} after expiry: ${verdict(after - start < 200 * 1024)}`,
  );
  await server.stop();
}

async function cycling() {
  console.log('\n3. one connection: create then unsubscribe, 64 times (target: it holds at most');
  console.log('   --max-sessions-per-connection sessions; resident memory within 200 MB of the start after expiry)');
  const server = await startServer(['--orphan-timeout', '3']);
  const start = server.status().rssKb;
  const raw = await rawSocket(server);
  let created = 0;
  for (let i = 0; i < 64; ++i) {
    raw.send({ v: 1, type: 'create', id: 2 * i, expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', box: [-5, 5, -5, 5, -5, 5], constraints: { triangles: 20000 } });
    const reply = await raw.reply(2 * i);
    if (reply.type !== 'created') continue;
    ++created;
    raw.send({ v: 1, type: 'unsubscribe', id: 2 * i + 1, session: reply.session });
    await raw.reply(2 * i + 1);
  }
  const held = (await server.metrics()).get('isomesh_sessions');
  const peak = server.status().rssKb;
  await until(async () => (await server.metrics()).get('isomesh_sessions') === 0, { timeoutMs: 60000, what: 'sessions to expire' });
  await sleep(2000);
  const after = server.status().rssKb;
  console.log(`   ${created} of 64 created, ${held} held; resident ${mb(start)} -> ${mb(peak)} -> ${mb(after)} after expiry: ${verdict(held <= 16 && after - start < 200 * 1024)}`);
  raw.socket.terminate();
  await server.stop();
}

async function descriptors() {
  console.log('\n4. out of file descriptors: prlimit --nofile=64, 100 idle TCP connections (target: under 5% of a core)');
  const server = await startServer([], { prefix: ['prlimit', '--nofile=64'] });
  const idleStart = cpuSeconds(server.pid);
  await sleep(5000);
  const idle = (cpuSeconds(server.pid) - idleStart) / 5;
  const sockets = [];
  for (let i = 0; i < 100; ++i) {
    const socket = net.connect(server.port, '127.0.0.1');
    socket.on('error', () => {});
    sockets.push(socket);
  }
  await sleep(500);
  const logBefore = server.log.length;
  const busyStart = cpuSeconds(server.pid);
  await sleep(5000);
  const busy = (cpuSeconds(server.pid) - busyStart) / 5;
  let health = 'refused';
  try {
    health = `${(await fetch(`${server.httpUrl}/healthz`, { signal: AbortSignal.timeout(5000) })).status}`;
  } catch {
    // stays 'refused'
  }
  const lines = server.log.length - logBefore;
  const metrics = await server.metrics();
  console.log(`   CPU ${(100 * busy).toFixed(2)}% of a core (idle: ${(100 * idle).toFixed(2)}%); /healthz ${health}; ${lines} log lines in 5 s;` +
    ` ${metrics.get('isomesh_accept_errors_total')} failed accepts, ${metrics.get('isomesh_http_evicted_total')} connections evicted: ${verdict(busy < 0.05)}`);
  for (const socket of sockets) socket.destroy();
  await server.stop();
}

async function memoryPerTriangle() {
  console.log('\n5. memory per triangle (gyroid on [-5,5]^3, 4 sessions of 250,000 triangles)');
  const server = await startServer(['--max-triangles', '2000000']);
  await sleep(500);
  const base = server.status().rssKb;
  const connection = await client(server);
  const sessions = await Promise.all([0, 1, 2, 3].map((k) =>
    connection.create({ expression: 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0', box: [-5 - 0.1 * k, 5, -5, 5, -5, 5], constraints: { triangles: 250000 } })));
  await Promise.all(sessions.map((s) => converged(s, 180000)));
  const held = server.status().rssKb;
  const triangles = sessions.reduce((sum, s) => sum + s.lastConverged.triangles, 0);
  const estimate = (await server.metrics()).get('isomesh_memory_estimate_bytes');
  await Promise.all(sessions.map((s) => s.close()));
  await sleep(2500);
  const after = server.status().rssKb;
  const perTriangle = ((held - base) * 1024) / triangles;
  console.log(`   ${triangles} triangles: resident ${mb(base)} -> ${mb(held)}: ${perTriangle.toFixed(0)} bytes per triangle` +
    ` (the server's estimate: ${(estimate / triangles).toFixed(0)} bytes per triangle, ${(estimate / (1 << 20)).toFixed(0)} MB);` +
    ` ${mb(after)} once closed`);
  // Not this part's subject, but worth knowing: what the frame checks found (issue 10's defects).
  if (connection.checker.problems.length > 0) console.log(`   frame checks: ${connection.checker.problems.slice(0, 3).join('; ')}`);
  connection.checker.problems.length = 0;
  connection.close();
  await server.stop();
}

if (wanted(1)) await regions();
if (wanted(2)) await disconnects();
if (wanted(3)) await cycling();
if (wanted(4)) await descriptors();
if (wanted(5)) await memoryPerTriangle();

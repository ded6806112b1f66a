// Benchmark of scale-out (not part of the test command): the compose deployment on loopback
// (tests/server/node/cluster.js: Redis, isomesh servers, HAProxy with deploy/haproxy.cfg) with one
// server and with three, the same clients through HAProxy:
//   1. create rate: CONNECTIONS clients (each its own route), each creating a session, waiting for
//      its first mesh (the keyframe decoded and applied), closing it, again, for SECONDS;
//   2. first-mesh latency p50/p99 over those creates (from sending `create`);
//   3. the session store's write latency p50/p99 (save and remove, from the servers' /metrics
//      histogram isomesh_store_write_seconds, interpolated within its 10-per-decade buckets);
// and, as the baselines of the same run, one server reached directly (no HAProxy) with its
// sessions in memory (--store none) and with its default SQLite store. A warm-up run comes first
// (the client's WebAssembly decoder and JIT); then every configuration runs ROUNDS times in turn,
// and the ratios compare the means, so that a machine shared with other work biases no one.
//
//   (cd tests/server/node && npm ci) && node bench/cluster_bench.mjs [--seconds S] [--connections N] [--threads T] [--rounds R]
//
// --threads: worker threads per server (default: one per core, the compose file's setting).

import { startCluster } from '../tests/server/node/cluster.js';
import { WebSocket, decoder, startServer } from '../tests/server/node/harness.js';
import { connect } from '../clients/js/src/index.js';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const option = (name, fallback) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const SECONDS = Number(option('seconds', 8));
const CONNECTIONS = Number(option('connections', 16));
const THREADS = option('threads', null);
const ROUNDS = Number(option('rounds', 2));

const SURFACES = [
  { expression: 'x^2+y^2+z^2=a', parameters: { a: 4 } },
  { expression: '(sqrt(x^2+y^2)-1.8)^2+z^2=0.5' },
  { expression: 'x^2+y^2+z^2+2cos(2x)=5' },
  { expression: '10x^2+y^2+z^2=5' },
];

function percentile(values, p) {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}

/** Closed loop of create -> first mesh -> close on every connection for `seconds`. */
async function createLoop(url, seconds = SECONDS) {
  const draco = await decoder();
  const clients = await Promise.all(Array.from({ length: CONNECTIONS }, () => connect(url, { decoder: draco, WebSocket })));
  const latencies = [];
  let errors = 0;
  const end = performance.now() + seconds * 1000;
  const started = performance.now();
  await Promise.all(clients.map(async (client, k) => {
    for (let n = 0; performance.now() < end; ++n) {
      const surface = SURFACES[(k + n) % SURFACES.length];
      const t0 = performance.now();
      try {
        // A budget of 1 triangle: phase 1 only, so that the first mesh is the whole stream.
        const session = await client.create({ ...surface, box: [-3, 3, -3, 3, -3, 3], constraints: { triangles: 1 } });
        if (!session.mesh.synchronized) await session.once('keyframe');
        latencies.push(performance.now() - t0);
        await session.close();
      } catch {
        ++errors;
      }
    }
  }));
  const elapsed = (performance.now() - started) / 1000;
  for (const client of clients) client.close();
  return { rate: latencies.length / elapsed, p50: percentile(latencies, 0.5), p99: percentile(latencies, 0.99), creates: latencies.length, errors };
}

/** Bucket counts of histogram `name` summed over `servers`' /metrics: [[le, cumulative]...]. */
async function histogram(servers, name) {
  const sums = new Map();
  for (const server of servers) {
    for (const [key, value] of await server.metrics()) {
      const match = new RegExp(`^${name}_bucket\\{le="([^"]+)"\\}$`).exec(key);
      if (match) sums.set(match[1], (sums.get(match[1]) ?? 0) + value);
    }
  }
  return [...sums].map(([le, count]) => [le === '+Inf' ? Infinity : Number(le), count]).sort((a, b) => a[0] - b[0]);
}

/** The p-quantile of a cumulative histogram, interpolated linearly within its bucket (ms). */
function quantile(buckets, p) {
  const total = buckets.at(-1)[1];
  if (total === 0) return NaN;
  const rank = p * total;
  let [lower, below] = [0, 0];
  for (const [le, cumulative] of buckets) {
    if (cumulative >= rank) {
      if (!Number.isFinite(le)) return lower * 1000;
      return 1000 * (lower + ((le - lower) * (rank - below)) / Math.max(1, cumulative - below));
    }
    [lower, below] = [le, cumulative];
  }
  return NaN;
}

/** Subtracts `before` from `after`, bucket by bucket. */
function delta(after, before) {
  return after.map(([le, count], i) => [le, count - (before[i]?.[1] ?? 0)]);
}

async function measure(label, url, servers) {
  const before = await histogram(servers, 'isomesh_store_write_seconds');
  const result = await createLoop(url);
  const writes = delta(await histogram(servers, 'isomesh_store_write_seconds'), before);
  result.storeWrites = writes.at(-1)?.[1] ?? 0;
  result.storeP50 = quantile(writes, 0.5);
  result.storeP99 = quantile(writes, 0.99);
  const fmt = (x) => (Number.isFinite(x) ? x.toFixed(2) : '   -');
  console.log(`   ${label.padEnd(34)} ${result.rate.toFixed(1).padStart(7)} creates/s   first mesh p50 ${fmt(result.p50).padStart(6)} ms` +
    `  p99 ${fmt(result.p99).padStart(7)} ms   store writes ${String(result.storeWrites).padStart(5)}: p50 ${fmt(result.storeP50)} ms  p99 ${fmt(result.storeP99)} ms` +
    (result.errors ? `   ${result.errors} errors` : ''));
  return result;
}

async function direct(label, args, warmUp = false) {
  const server = await startServer([...args, ...(THREADS ? ['--threads', THREADS] : ['--threads', '0'])]);
  try {
    if (warmUp) await createLoop(server.wsUrl, 2);
    return await measure(label, server.wsUrl, [server]);
  } finally {
    await server.stop();
  }
}

async function throughCluster(replicas) {
  const cluster = await startCluster({ replicas, threads: THREADS });
  try {
    return await measure(`HAProxy + Redis, ${replicas} server${replicas > 1 ? 's' : ''}`, cluster.wsUrl, cluster.servers);
  } finally {
    await cluster.stop();
  }
}

const mean = (results, key) => results.reduce((sum, r) => sum + r[key], 0) / results.length;

console.log(`cluster benchmark: ${CONNECTIONS} connections, ${SECONDS} s per configuration, ${ROUNDS} rounds, ` +
  `worker threads per server: ${THREADS ?? 'one per core'}`);
const dir = mkdtempSync(join(tmpdir(), 'isomesh-bench-'));
try {
  const runs = { memory: [], sqlite: [], one: [], three: [] };
  for (let round = 1; round <= ROUNDS; ++round) {
    console.log(`\n   round ${round}`);
    runs.memory.push(await direct('one server direct, --store none', ['--store', 'none'], round === 1));
    runs.sqlite.push(await direct('one server direct, SQLite', ['--store', `sqlite:${join(dir, `sessions-${round}.db`)}`]));
    runs.one.push(await throughCluster(1));
    runs.three.push(await throughCluster(3));
  }
  const ratio = (a, b, key) => (mean(runs[a], key) / mean(runs[b], key)).toFixed(2);
  console.log(`\n   ratios of the means over ${ROUNDS} rounds`);
  console.log(`   3 servers / 1 server (HAProxy + Redis): create rate ${ratio('three', 'one', 'rate')}x, ` +
    `first-mesh p99 ${ratio('three', 'one', 'p99')}x`);
  console.log(`   1 server through HAProxy + Redis / direct in memory: create rate ${ratio('one', 'memory', 'rate')}x, ` +
    `first-mesh p99 ${ratio('one', 'memory', 'p99')}x`);
  console.log(`   SQLite / in memory (direct): create rate ${ratio('sqlite', 'memory', 'rate')}x, ` +
    `first-mesh p99 ${ratio('sqlite', 'memory', 'p99')}x`);
  const writes = (key) => `p50 ${mean(runs[key], 'storeP50').toFixed(3)} ms, p99 ${mean(runs[key], 'storeP99').toFixed(3)} ms`;
  console.log(`   store write latency: SQLite ${writes('sqlite')}; Redis with 1 server ${writes('one')}, with 3 ${writes('three')}`);
} finally {
  rmSync(dir, { recursive: true, force: true });
}

// The cluster of deploy/compose.yaml on loopback (tests/server/node/cluster.js): Redis, three
// isomesh-servers and HAProxy with deploy/haproxy.cfg, clients of the client library connecting
// through HAProxy. Servers are killed with SIGKILL (kill -9) and stopped with SIGTERM while
// clients watch and move sliders; every session must go on, on the server HAProxy now routes its
// clients to, rebuilt from Redis, and converge to the mesh of its definition: the same triangles
// at bit-equal positions as a reference server computes, with no session lost or duplicated and
// no acknowledged update lost. Redis itself is stopped and restarted mid-run.
//
//   cd tests/server/node && npm ci --no-audit --no-fund && node --test cluster.test.js

import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { promisify } from 'node:util';

import { DEPLOY, composeServices, manifest, startCluster } from './cluster.js';
import { WebSocket, decoder, positionTriangles, startServer, until } from './harness.js';
import { connect } from '../../../clients/js/src/index.js';

const CONNECTIONS = 50;
const SESSIONS_PER_CONNECTION = 4; // 200 sessions
const TRIANGLES = 800;
const UPDATES = 3; // per session, in flight while a server is killed

// Surfaces with a parameter `a`; session j meshes SURFACES[j % 5].
const SURFACES = [
  { expression: 'x^2+y^2+z^2=a', a: 4 },
  { expression: '(sqrt(x^2+y^2)-1.8)^2+z^2=a', a: 0.5 },
  { expression: 'x^2+y^2+z^2+2cos(2x)=a', a: 5 },
  { expression: '10x^2+y^2+z^2=a', a: 5 },
  { expression: '((x-1)^2+y^2-1)((x+1)^2+y^2-1)+z^2=a', a: 0.3 },
];

/**
 * The definition of session j after `step` updates. Every update moves the slider and the box:
 * a new box makes the server mesh from scratch, so the converged mesh depends on the definition
 * alone, not on when the updates came (parameter-only updates refine from the mesh on hand,
 * PROTOCOL.md 3.6), and every session can be checked against a reference server.
 */
function definition(j, step = 0) {
  const { expression, a } = SURFACES[j % SURFACES.length];
  const half = 3 * (1 + 0.02 * step);
  return {
    expression,
    parameters: { a: a * (1 + 0.03 * step) },
    box: [-half, half, -half, half, -half, half],
    constraints: { triangles: TRIANGLES },
  };
}

function clientOf(url) {
  return decoder().then((d) => connect(url, { decoder: d, WebSocket }));
}

/** Meshes of definitions made by a server of its own (no store, no cluster), by definition. */
class References {
  constructor(server, connection) {
    this.server = server;
    this.connection = connection;
    this.meshes = new Map();
  }

  static async start() {
    const server = await startServer(['--threads', '1']);
    return new References(server, await clientOf(server.wsUrl));
  }

  async of(fields) {
    const key = JSON.stringify(fields);
    if (!this.meshes.has(key)) {
      const session = await this.connection.create(fields);
      await until(() => session.converged, { timeoutMs: 60000, what: 'a reference mesh' });
      this.meshes.set(key, positionTriangles(session.mesh));
      await session.close();
    }
    return this.meshes.get(key);
  }

  async stop() {
    this.connection.close();
    assert.equal((await this.server.stop()).code, 0);
  }
}

/** Sum of a metric over the servers that run. */
async function total(servers, name) {
  let sum = 0;
  for (const server of servers) sum += (await server.metrics()).get(name) ?? 0;
  return sum;
}

/** The running server holding the most sessions, and its index. */
async function busiest(cluster) {
  let best = -1;
  let most = -1;
  for (let i = 0; i < cluster.servers.length; ++i) {
    const server = cluster.servers[i];
    if (!server?.alive) continue;
    const sessions = (await server.metrics()).get('isomesh_sessions');
    if (sessions > most) [best, most] = [i, sessions];
  }
  return { index: best, sessions: most };
}

function running(cluster) {
  return cluster.servers.filter((s) => s?.alive);
}

/** Resolves once every session holds the final mesh of its latest version. */
async function allConverged(sessions, what) {
  await until(() => sessions.every((s) => s.converged && !s.resubscribing), {
    timeoutMs: 120000,
    everyMs: 50,
    what: `${what}: ${sessions.filter((s) => !s.converged).length} sessions still converging`,
  });
}

/** Every session's mesh equals the reference of its definition; returns the mismatches. */
async function mismatches(sessions, references, definitions) {
  const wrong = [];
  for (let j = 0; j < sessions.length; ++j) {
    const expected = await references.of(definitions[j]);
    if (JSON.stringify(positionTriangles(sessions[j].mesh)) !== JSON.stringify(expected)) wrong.push(sessions[j].id);
  }
  return wrong;
}

describe('cluster: Redis, three servers and HAProxy from deploy/', () => {
  let cluster;
  let references;
  before(async () => {
    [cluster, references] = await Promise.all([startCluster(), References.start()]);
  });
  after(async () => {
    await references?.stop();
    for (const code of (await cluster?.stop()) ?? []) assert.equal(code, 0, 'servers exit 0 on SIGTERM');
  });

  test('200 sessions over 50 connections survive kill -9 of a server, then again with updates in flight, then a SIGTERM', async (t) => {
    const clients = await Promise.all(Array.from({ length: CONNECTIONS }, () => clientOf(cluster.wsUrl)));
    const closedEvents = [];
    try {
      const sessions = [];
      await Promise.all(clients.map(async (c, k) => {
        for (let i = 0; i < SESSIONS_PER_CONNECTION; ++i) {
          const j = k * SESSIONS_PER_CONNECTION + i;
          sessions[j] = await c.create(definition(j));
          sessions[j].on('closed', (m) => closedEvents.push([sessions[j].id, m.reason]));
        }
      }));
      const definitions = sessions.map((_, j) => definition(j));
      assert.equal(new Set(sessions.map((s) => s.id)).size, CONNECTIONS * SESSIONS_PER_CONNECTION);
      await allConverged(sessions, 'first meshes');
      assert.deepEqual(await mismatches(sessions, references, definitions), [], 'meshes before any failure');
      assert.equal(await total(running(cluster), 'isomesh_sessions'), sessions.length);
      assert.equal(await cluster.redis.records(), sessions.length, 'one record per session');
      assert.equal(Number(await cluster.redis.cli('dbsize')), 2 * (sessions.length), 'and one view key each');

      // ---- kill -9 of the busiest server --------------------------------------------------
      const victim = await busiest(cluster);
      assert.ok(victim.sessions > 0);
      const disconnected = new Set();
      clients.forEach((c, k) => c.on('disconnected', () => disconnected.add(k)));
      let started = performance.now();
      await cluster.servers[victim.index].kill();
      await until(() => disconnected.size > 0, { what: 'clients to notice' });
      await allConverged(sessions, 'after kill -9');
      t.diagnostic(`kill -9 of ${cluster.names[victim.index]} (${victim.sessions} sessions, ${disconnected.size} connections): ` +
        `all 200 converged again after ${(performance.now() - started).toFixed(0)} ms`);
      for (const k of disconnected) assert.ok(clients[k].reconnects >= 1, `client ${k} reconnected`);
      assert.deepEqual(await mismatches(sessions, references, definitions), [], 'meshes after kill -9');
      assert.equal(await total(running(cluster), 'isomesh_sessions'), sessions.length, 'no session lost or duplicated');
      assert.equal(await total(running(cluster), 'isomesh_sessions_restored_total'), victim.sessions);
      assert.deepEqual(closedEvents, []);

      // ---- the victim is back; updates in flight while another server is killed -------------
      await cluster.startServer(victim.index);
      await cluster.waitForStatuses(['UP', 'UP', 'UP']);
      let acknowledged = 0;
      const sliders = sessions.map(async (session, j) => {
        for (let step = 1; step <= UPDATES; ++step) {
          const { parameters, box } = definition(j, step);
          await session.update({ parameters, box });
          ++acknowledged;
          await new Promise((resolve) => setTimeout(resolve, 50 + 100 * Math.random()));
        }
      });
      await until(() => acknowledged >= sessions.length / 2, { what: 'updates under way' });
      const second = await busiest(cluster);
      await cluster.servers[second.index].kill();
      const killedAt = acknowledged;
      started = performance.now();
      await Promise.all(sliders);
      assert.ok(killedAt < sessions.length * UPDATES, 'the kill came while updates were in flight');
      const finals = sessions.map((_, j) => definition(j, UPDATES));
      await allConverged(sessions, 'after kill -9 with updates in flight');
      t.diagnostic(`kill -9 of ${cluster.names[second.index]} (${second.sessions} sessions) after ${killedAt} of ` +
        `${sessions.length * UPDATES} updates: all acknowledged and converged ${(performance.now() - started).toFixed(0)} ms later`);
      for (let j = 0; j < sessions.length; ++j) {
        const state = sessions[j].state;
        assert.deepEqual(state.parameters, finals[j].parameters, `session ${j}: the last update holds`);
        assert.deepEqual(state.box, finals[j].box);
        assert.ok(state.version >= 1 + UPDATES, `session ${j}: version ${state.version}`);
      }
      assert.deepEqual(await mismatches(sessions, references, finals), [], 'meshes after updates and kill -9');
      assert.equal(await total(running(cluster), 'isomesh_sessions'), sessions.length, 'no session lost or duplicated');
      assert.equal(await cluster.redis.records(), sessions.length);
      assert.equal(Number(await cluster.redis.cli('dbsize')), 2 * (sessions.length), 'and one view key each');
      assert.deepEqual(closedEvents, []);

      // ---- graceful: SIGTERM drains a server; its sessions move ----------------------------
      const third = await busiest(cluster);
      started = performance.now();
      const { code } = await cluster.servers[third.index].stop();
      assert.equal(code, 0);
      await allConverged(sessions, 'after SIGTERM');
      t.diagnostic(`SIGTERM of ${cluster.names[third.index]} (${third.sessions} sessions): exit 0, ` +
        `all converged ${(performance.now() - started).toFixed(0)} ms later`);
      assert.deepEqual(await mismatches(sessions, references, finals), [], 'meshes after SIGTERM');
      assert.equal(await total(running(cluster), 'isomesh_sessions'), sessions.length);
      assert.deepEqual(closedEvents, []);
    } finally {
      for (const c of clients) c.close();
    }
  });
});

describe('cluster: Redis stopped and restarted mid-run', () => {
  test('live sessions keep streaming, new sessions and updates get store_unavailable, full service after', async () => {
    const cluster = await startCluster();
    const clients = [];
    try {
      for (let k = 0; k < 6; ++k) clients.push(await clientOf(cluster.wsUrl));
      const sessions = await Promise.all(clients.map((c, k) => c.create(definition(k))));
      await allConverged(sessions, 'first meshes');
      const meshes = sessions.map((s) => positionTriangles(s.mesh));
      const servers = cluster.servers;

      await cluster.redis.stop();
      const readiness = () => Promise.all(servers.map(async (s) => {
        const response = await fetch(`${s.httpUrl}/readyz`);
        return `${response.status} ${(await response.text()).trim()}`;
      }));
      await until(async () => (await readiness()).every((r) => r === '503 session store unreachable'), { what: 'every server to report the store down' });
      for (const s of servers) assert.equal((await fetch(`${s.httpUrl}/healthz`)).status, 200, 'alive all the same');
      await cluster.waitForStatuses(['DOWN', 'DOWN', 'DOWN']); // HAProxy sends no new connections

      await assert.rejects(clients[0].create(definition(0)), (e) => e.code === 'store_unavailable');
      await assert.rejects(sessions[1].update({ parameters: { a: 1 } }), (e) => e.code === 'store_unavailable');
      // Live sessions stream on: a fresh keyframe of each, the mesh it had.
      await Promise.all(sessions.map((s) => s.resync()));
      await until(() => sessions.every((s) => s.mesh.synchronized && !s.resyncPending), { what: 'keyframes' });
      assert.deepEqual(sessions.map((s) => positionTriangles(s.mesh)), meshes);
      for (const s of servers) {
        const m = await s.metrics();
        assert.equal(m.get('isomesh_store_up'), 0);
        assert.ok(m.get('isomesh_store_errors_total') > 0);
        assert.ok(m.get('isomesh_errors_total{code="store_unavailable"}') >= 0);
        assert.ok(s.alive);
      }

      await cluster.redis.start(); // on its append-only file: the records are back
      await until(async () => (await readiness()).every((r) => r === '200 ready'), { what: 'every server to see the store again' });
      await cluster.waitForStatuses(['UP', 'UP', 'UP']);
      const updated = await sessions[1].update({ parameters: { a: 0.55 } });
      assert.equal(updated.version, 2);
      const created = await clients[0].create(definition(7));
      await allConverged([...sessions, created], 'after Redis came back');
      assert.equal(await cluster.redis.records(), sessions.length + 1);
      assert.equal(Number(await cluster.redis.cli('dbsize')), 2 * (sessions.length + 1), 'and one view key each');
      // A new connection through HAProxy reaches a session's server by its route.
      const late = await decoder().then((d) => connect(cluster.wsUrl, { decoder: d, WebSocket, route: sessions[2].id.slice(0, 8) }));
      clients.push(late);
      const watched = await late.subscribe(sessions[2].id);
      await until(() => watched.converged, { what: 'the late subscriber' });
      assert.deepEqual(positionTriangles(watched.mesh), meshes[2]);
    } finally {
      for (const c of clients) c.close();
      for (const code of await cluster.stop()) assert.equal(code, 0);
    }
  });
});

describe('deployment files', () => {
  test('haproxy.cfg is valid for compose (static servers) and Kubernetes (DNS discovery)', async () => {
    const check = (env) => promisify(execFile)('haproxy', ['-c', '-f', join(DEPLOY, 'haproxy.cfg')], { env: { ...process.env, ...env } });
    const compose = composeServices().haproxy.environment;
    await check({ ...compose, ISOMESH_SERVER_1: '127.0.0.1:1', ISOMESH_SERVER_2: '127.0.0.1:2', ISOMESH_SERVER_3: '127.0.0.1:3' });
    const haproxy = manifest('haproxy.yaml').find((d) => d.kind === 'Deployment');
    const env = Object.fromEntries(haproxy.spec.template.spec.containers[0].env.filter((e) => e.value).map((e) => [e.name, e.value]));
    await check({ ...env, ISOMESH_SERVICE_DNS: env.ISOMESH_SERVICE_DNS.replace('$(POD_NAMESPACE)', 'default') });
  });

  test('the Kubernetes Deployment runs the compose environment, probes what the server answers, outlasts the drain', async () => {
    const [deployment, service] = manifest('isomesh.yaml');
    assert.equal(deployment.kind, 'Deployment');
    assert.equal(service.kind, 'Service');
    assert.equal(service.spec.clusterIP, 'None');
    assert.deepEqual(service.spec.selector, deployment.spec.template.metadata.labels);
    const container = deployment.spec.template.spec.containers[0];
    const env = Object.fromEntries(container.env.map((e) => [e.name, e.value]));
    assert.deepEqual(env, composeServices()['isomesh-1'].environment, 'the environment the cluster test runs');
    assert.equal(String(container.ports[0].containerPort), env.ISOMESH_PORT);
    assert.equal(container.readinessProbe.httpGet.path, '/readyz');
    assert.equal(container.livenessProbe.httpGet.path, '/healthz');
    const { stdout } = await promisify(execFile)(join(process.env.ISOMESH_BIN_DIR ?? join(DEPLOY, '../build/bin'), 'isomesh-server'), ['--help']);
    const drain = Number(/--drain-timeout \(ISOMESH_DRAIN_TIMEOUT, default '([\d.]+)'\)/.exec(stdout)[1]);
    assert.ok(deployment.spec.template.spec.terminationGracePeriodSeconds > drain + 5);
    const haproxy = manifest('haproxy.yaml').find((d) => d.kind === 'Deployment');
    const dns = haproxy.spec.template.spec.containers[0].env.find((e) => e.name === 'ISOMESH_SERVICE_DNS').value;
    assert.match(dns, new RegExp(`^${service.metadata.name}\\.\\$\\(POD_NAMESPACE\\)\\.svc\\.cluster\\.local:${service.spec.ports[0].port}$`));
    // The probes' paths as the server answers them (a server configured like a replica).
    const server = await startServer(['--store', 'none']);
    try {
      assert.equal(await (await fetch(`${server.httpUrl}${container.readinessProbe.httpGet.path}`)).text(), 'ready\n');
      assert.equal((await fetch(`${server.httpUrl}${container.livenessProbe.httpGet.path}`)).status, 200);
    } finally {
      assert.equal((await server.stop()).code, 0);
    }
  });
});

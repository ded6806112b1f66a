// deploy/compose.yaml on loopback: the processes its services name (redis-server, the
// isomesh-server replicas, haproxy), with the same commands, environment and configuration files
// (deploy/redis.conf, deploy/haproxy.cfg), since Docker cannot run on the test machines.
//
// What changes from containers to loopback, and only that: service host names become 127.0.0.1,
// ports become free loopback ports, Redis's working folder a temporary one, each server gets one
// worker thread unless asked otherwise (the test machine has 2 cores for 3 servers) and no web
// root. Every process is stopped by stop(); nothing is left running.

import { execFile, spawn } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';
import { promisify } from 'node:util';

import { parse, parseAllDocuments } from 'yaml';

import { startServer, until } from './harness.js';

export const DEPLOY = fileURLToPath(new URL('../../../deploy/', import.meta.url));

/** The services of deploy/compose.yaml. */
export function composeServices() {
  return parse(readFileSync(join(DEPLOY, 'compose.yaml'), 'utf8')).services;
}

/** The documents of a Kubernetes manifest in deploy/k8s. */
export function manifest(name) {
  return parseAllDocuments(readFileSync(join(DEPLOY, 'k8s', name), 'utf8')).map((d) => d.toJS());
}

/** A free TCP port on 127.0.0.1 (free when asked: the caller binds it soon after). */
export function freePort() {
  return new Promise((resolvePort, reject) => {
    const server = createServer();
    server.once('error', reject);
    server.listen(0, '127.0.0.1', () => {
      const { port } = server.address();
      server.close(() => resolvePort(port));
    });
  });
}

/** A service's command with container paths of its volumes replaced by the files in deploy/. */
function hostCommand(service) {
  const mounts = new Map();
  for (const volume of service.volumes ?? []) {
    const [source, target] = volume.split(':');
    if (source.startsWith('.')) mounts.set(target, resolve(DEPLOY, source));
  }
  return service.command.map((arg) => mounts.get(arg) ?? arg);
}

/** A service's environment with `service:port` references turned into loopback addresses. */
function hostEnvironment(service, ports) {
  const env = {};
  for (const [key, value] of Object.entries(service.environment ?? {})) {
    env[key] = String(value).replace(/\b([a-z][a-z0-9-]*):(\d+)\b/g, (match, host) =>
      ports.has(host) ? `127.0.0.1:${ports.get(host)}` : match);
  }
  return env;
}

/**
 * Spawns `command` and resolves with {child, log, exited} once a line of its output matches
 * `ready` (a RegExp) or, for a function, once `ready()` resolves true (polled).
 */
function spawnUntil(command, { env, cwd, ready, what, timeoutMs = 20000 }) {
  const child = spawn(command[0], command.slice(1), { env: { ...process.env, ...env }, cwd, stdio: ['ignore', 'pipe', 'pipe'] });
  const log = [];
  const exited = new Promise((done) => child.once('exit', (code, signal) => done({ code, signal })));
  return new Promise((resolveStart, reject) => {
    const timer = setTimeout(() => {
      child.kill('SIGKILL');
      reject(new Error(`${what} not ready within ${timeoutMs} ms:\n${log.join('\n')}`));
    }, timeoutMs);
    let started = false;
    const done = () => {
      if (started) return;
      started = true;
      clearTimeout(timer);
      resolveStart({ child, log, exited });
    };
    exited.then(({ code, signal }) => {
      clearTimeout(timer);
      if (!started) reject(new Error(`${what} exited early (${code ?? signal}):\n${log.join('\n')}`));
    });
    for (const stream of [child.stdout, child.stderr]) {
      createInterface({ input: stream }).on('line', (line) => {
        log.push(line);
        if (log.length > 200) log.shift();
        if (ready instanceof RegExp && ready.test(line)) done();
      });
    }
    if (typeof ready === 'function') {
      const poll = async () => {
        if (started || child.exitCode !== null) return;
        if (await ready().catch(() => false)) done();
        else setTimeout(poll, 50);
      };
      poll();
    }
  });
}

async function stopProcess(child, exited, signal = 'SIGTERM') {
  if (child.exitCode === null && child.signalCode === null) child.kill(signal);
  const timer = setTimeout(() => child.kill('SIGKILL'), 10000);
  const result = await exited;
  clearTimeout(timer);
  return result;
}

/** Redis as the compose service `redis` runs it; start() again restarts it on its data. */
class Redis {
  constructor(service, port) {
    this.service = service;
    this.port = port;
    this.dir = mkdtempSync(join(tmpdir(), 'isomesh-redis-'));
    this.process = null;
  }

  async start() {
    const overrides = ['--port', String(this.port), '--bind', '127.0.0.1'];
    this.process = await spawnUntil([...hostCommand(this.service), ...overrides], {
      cwd: this.dir, // its data folder (the image's WORKDIR)
      ready: /Ready to accept connections/,
      what: 'redis-server',
    });
  }

  /** SIGTERM: Redis flushes its append-only file and exits. */
  async stop() {
    if (!this.process) return;
    const { child, exited } = this.process;
    this.process = null;
    await stopProcess(child, exited);
  }

  /** Runs redis-cli with `args`; resolves with its output. */
  async cli(...args) {
    const { stdout } = await promisify(execFile)('redis-cli', ['-p', String(this.port), ...args]);
    return stdout.trim();
  }

  /** The number of session records (each also has a key for its view id). */
  async records() {
    return Number(await this.cli('eval', "return #redis.call('keys', 'isomesh:session:*')", '0'));
  }

  remove() {
    rmSync(this.dir, { recursive: true, force: true });
  }
}

/** The isomesh servers and HAProxy of deploy/compose.yaml on loopback, sharing one Redis. */
class Cluster {
  constructor(services, names, ports, threads) {
    this.services = services;
    this.threads = threads; // worker threads per server; null: compose's (one per core)
    this.names = names; // compose service names of the servers, 'isomesh-1'...
    this.ports = ports; // compose service name -> loopback port
    this.redis = new Redis(services.redis, ports.get('redis'));
    this.servers = []; // harness server handles, by index
    this.haproxy = null;
  }

  /** The environment compose gives server `name`, on loopback. */
  serverEnvironment(name) {
    const env = {
      ...hostEnvironment(this.services[name], this.ports),
      ISOMESH_BIND: '127.0.0.1',
      ISOMESH_PORT: String(this.ports.get(name)),
      ISOMESH_WEB_ROOT: '',
    };
    if (this.threads !== null) env.ISOMESH_THREADS = String(this.threads);
    return env;
  }

  /** Starts server `i` (again, after a kill: same port, same environment). */
  async startServer(i) {
    const name = this.names[i];
    const [program, ...args] = hostCommand(this.services[name]);
    if (program !== 'isomesh-server' || args.length > 0) throw new Error(`unexpected command of ${name}: ${program} ${args}`);
    this.servers[i] = await startServer([], { bare: true, env: this.serverEnvironment(name) });
    return this.servers[i];
  }

  async startHaproxy() {
    const env = hostEnvironment(this.services.haproxy, this.ports);
    for (const n of [2, 3]) if (!this.names.includes(`isomesh-${n}`)) delete env[`ISOMESH_SERVER_${n}`];
    env.ISOMESH_LISTEN = `127.0.0.1:${this.ports.get('haproxy')}`;
    env.ISOMESH_STATS = `127.0.0.1:${this.ports.get('stats')}`;
    this.haproxy = await spawnUntil(hostCommand(this.services.haproxy), {
      env,
      ready: async () => (await fetch(`http://127.0.0.1:${this.ports.get('stats')}/stats;csv`)).ok,
      what: 'haproxy',
    });
    this.wsUrl = `ws://127.0.0.1:${this.ports.get('haproxy')}/ws`;
  }

  /** Server name -> HAProxy's status of it ('UP', 'DOWN', ...), from its statistics page. */
  async statuses() {
    const text = await (await fetch(`http://127.0.0.1:${this.ports.get('stats')}/stats;csv`)).text();
    const rows = text.split('\n').filter((line) => line.startsWith('isomesh,isomesh-'));
    return new Map(rows.map((row) => {
      const fields = row.split(',');
      return [fields[1], fields[17]];
    }));
  }

  /** Resolves once HAProxy reports `expected[i]` ('UP', 'DOWN') for server i. */
  async waitForStatuses(expected) {
    await until(async () => {
      const statuses = await this.statuses();
      return expected.every((status, i) => statuses.get(this.names[i]) === status);
    }, { timeoutMs: 20000, everyMs: 100, what: `HAProxy to report ${expected}` });
  }

  /** Every process stopped (SIGTERM), Redis's data removed. */
  async stop() {
    if (this.haproxy) await stopProcess(this.haproxy.child, this.haproxy.exited);
    this.haproxy = null;
    const codes = []; // of the servers still running
    for (const server of this.servers) if (server?.alive) codes.push((await server.stop()).code);
    this.servers = [];
    await this.redis.stop();
    this.redis.remove();
    return codes;
  }
}

/**
 * Starts deploy/compose.yaml on loopback with `replicas` (1 to 3) of its isomesh servers, each with
 * `threads` worker threads (null: compose's default, one per core); resolves once HAProxy reports
 * every server up.
 */
export async function startCluster({ replicas = 3, threads = 1 } = {}) {
  const names = ['isomesh-1', 'isomesh-2', 'isomesh-3'].slice(0, replicas);
  const ports = new Map();
  for (const name of ['redis', ...names, 'haproxy', 'stats']) ports.set(name, await freePort());
  const cluster = new Cluster(composeServices(), names, ports, threads);
  try {
    await cluster.redis.start();
    for (let i = 0; i < names.length; ++i) await cluster.startServer(i);
    await cluster.startHaproxy();
    await cluster.waitForStatuses(names.map(() => 'UP'));
  } catch (error) {
    await cluster.stop();
    throw error;
  }
  return cluster;
}

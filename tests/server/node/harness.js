// What the integration tests share: a real isomesh-server on a free loopback port (--port 0; the
// port comes from its "listening" log line), clients of the isomesh-client library (clients/js)
// over the `ws` package with Google's draco3d decoder, the server's /metrics and /proc status, and
// the `isomesh mesh` CLI for reference meshes.
//
// Binaries come from build/bin, or from $ISOMESH_BIN_DIR (e.g. a developer's own build folder).

import { spawn, execFile } from 'node:child_process';
import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';
import { promisify } from 'node:util';

import createDecoderModule from 'draco3d/draco_decoder_nodejs.js';
import WebSocket from 'ws';

import { connect, DracoMeshDecoder } from '../../../clients/js/src/index.js';

export { WebSocket };

const REPO = fileURLToPath(new URL('../../..', import.meta.url));
export const BIN_DIR = process.env.ISOMESH_BIN_DIR ?? join(REPO, 'build/bin');

let decoderPromise = null;
/** One Draco decoder (WebAssembly) for the whole test process. */
export function decoder() {
  decoderPromise ??= createDecoderModule({}).then((draco) => new DracoMeshDecoder(draco));
  return decoderPromise;
}

/** Resolves when `predicate()` holds, polling every `everyMs`; rejects after `timeoutMs`. */
export async function until(predicate, { timeoutMs = 20000, everyMs = 10, what = 'condition' } = {}) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    if (await predicate()) return;
    if (Date.now() > end) throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}`);
    await new Promise((resolve) => setTimeout(resolve, everyMs));
  }
}

/**
 * Starts isomesh-server with `args` added to the test defaults (sessions in memory only unless
 * `args` name a --store). Resolves with a handle:
 * {port, pid, wsUrl, httpUrl, log, stop(), kill(), metrics(), status()}.
 * `env`: the server's environment; `bare`: no default arguments (configured by `env` alone).
 */
export function startServer(args = [], { timeoutMs = 20000, env = process.env, bare = false } = {}) {
  const defaults = bare ? [] : ['--bind', '127.0.0.1', '--port', '0', '--threads', '2', '--web-root', '', '--store', 'none'];
  const fullArgs = [];
  for (let i = 0; i < defaults.length; i += 2) {
    if (!args.includes(defaults[i])) fullArgs.push(defaults[i], defaults[i + 1]);
  }
  fullArgs.push(...args);
  const child = spawn(join(BIN_DIR, 'isomesh-server'), fullArgs, { stdio: ['ignore', 'ignore', 'pipe'], env });
  const log = [];
  const exited = new Promise((resolve) => child.once('exit', (code, signal) => resolve({ code, signal })));
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => {
      child.kill('SIGKILL');
      reject(new Error(`no "listening" line within ${timeoutMs} ms:\n${log.join('\n')}`));
    }, timeoutMs);
    exited.then(({ code, signal }) => {
      clearTimeout(timer);
      reject(new Error(`isomesh-server exited early (${code ?? signal}):\n${log.join('\n')}`));
    });
    createInterface({ input: child.stderr }).on('line', (line) => {
      log.push(line);
      let entry;
      try {
        entry = JSON.parse(line);
      } catch {
        return;
      }
      if (entry.event !== 'listening') return;
      clearTimeout(timer);
      resolve(serverHandle(child, entry.port, log, exited));
    });
  });
}

function serverHandle(child, port, log, exited) {
  const httpUrl = `http://127.0.0.1:${port}`;
  return {
    port,
    pid: child.pid,
    httpUrl,
    wsUrl: `ws://127.0.0.1:${port}/ws`,
    log,
    exited,
    /** True until the process exits. */
    get alive() {
      return child.exitCode === null && child.signalCode === null;
    },
    /** SIGKILL (kill -9): no drain, nothing flushed; resolves once the process is gone. */
    async kill() {
      if (child.exitCode === null && child.signalCode === null) child.kill('SIGKILL');
      return exited;
    },
    /** SIGTERM, then SIGKILL after 10 s; resolves with {code, signal}. */
    async stop() {
      if (child.exitCode === null && child.signalCode === null) child.kill('SIGTERM');
      const timer = setTimeout(() => child.kill('SIGKILL'), 10000);
      const result = await exited;
      clearTimeout(timer);
      return result;
    },
    /** The /metrics samples by name (labels included verbatim), as numbers. */
    async metrics() {
      const text = await (await fetch(`${httpUrl}/metrics`)).text();
      const samples = new Map();
      for (const line of text.split('\n')) {
        if (line === '' || line.startsWith('#')) continue;
        const space = line.lastIndexOf(' ');
        samples.set(line.slice(0, space), Number(line.slice(space + 1)));
      }
      return samples;
    },
    /** VmRSS in kB and the thread count, from /proc. */
    status() {
      const text = readFileSync(`/proc/${child.pid}/status`, 'utf8');
      const field = (name) => Number(new RegExp(`^${name}:\\s+(\\d+)`, 'm').exec(text)[1]);
      return { rssKb: field('VmRSS'), threads: field('Threads') };
    },
  };
}

/** An isomesh-client connection to `server`. */
export async function client(server, options = {}) {
  return connect(server.wsUrl, { decoder: await decoder(), WebSocket, ...options });
}

/** Resolves once `session` holds the final mesh of its latest version. */
export async function converged(session, timeoutMs = 30000) {
  await until(() => session.converged, { timeoutMs, what: `session ${session.id} to converge` });
  return session;
}

/**
 * Resolves once a session followed by subscription (whose client library knows only the version it
 * subscribed to) holds the final mesh of function version `version`.
 */
export async function convergedAt(session, version, timeoutMs = 30000) {
  await until(
    () => {
      const last = session.lastConverged;
      return last?.version === version && session.mesh.synchronized &&
        session.mesh.functionVersion === version && session.mesh.sequence >= last.sequence;
    },
    { timeoutMs, what: `session ${session.id} to converge at version ${version}` },
  );
  return session;
}

/** The triangles of a SessionMesh as vertex-id triples, each rotated to start at its smallest id. */
export function canonicalTriangles(mesh) {
  return mesh.sortedTriangles().map(({ vertices }) => rotated(vertices)).sort(compareTriples);
}

/**
 * The triangles of a SessionMesh by the bits of their corners' float32 positions, each rotated to
 * start at its smallest corner (orientation kept), sorted: equal lists mean the same triangles at
 * bit-equal positions, whatever the triangle and vertex ids (a rebuilt session numbers anew).
 */
export function positionTriangles(mesh) {
  const { positions, indices } = mesh.toIndexed();
  const bits = new Uint32Array(positions.buffer, positions.byteOffset, positions.length);
  const corner = (v) => `${bits[3 * v].toString(16)},${bits[3 * v + 1].toString(16)},${bits[3 * v + 2].toString(16)}`;
  const out = [];
  for (let t = 0; t < indices.length; t += 3) {
    const c = [corner(indices[t]), corner(indices[t + 1]), corner(indices[t + 2])];
    const first = c.indexOf([...c].sort()[0]);
    out.push(`${c[first]} ${c[(first + 1) % 3]} ${c[(first + 2) % 3]}`);
  }
  return out.sort();
}

function rotated(v) {
  const first = v.indexOf(Math.min(...v));
  return [v[first], v[(first + 1) % 3], v[(first + 2) % 3]];
}

function compareTriples(a, b) {
  return a[0] - b[0] || a[1] - b[1] || a[2] - b[2];
}

/** True when every edge is used once in each direction: closed and consistently oriented. */
export function watertight(indices) {
  const directed = new Map();
  const key = (a, b) => a * 4294967296 + b;
  for (let t = 0; t < indices.length; t += 3) {
    for (let k = 0; k < 3; ++k) {
      const edge = key(indices[t + k], indices[t + ((k + 1) % 3)]);
      directed.set(edge, (directed.get(edge) ?? 0) + 1);
    }
  }
  if (directed.size === 0) return false;
  for (const [edge, uses] of directed) {
    const a = Math.floor(edge / 4294967296);
    const b = edge % 4294967296;
    if (uses !== 1 || directed.get(key(b, a)) !== 1) return false;
  }
  return true;
}

/**
 * Runs `isomesh mesh` and returns its mesh {positions: [[x, y, z]...], triangles: [[a, b, c]...]}
 * read back from an OBJ file (full double precision).
 */
export async function cliMesh(expression, { box, triangles }) {
  const dir = mkdtempSync(join(tmpdir(), 'isomesh-server-test-'));
  try {
    const file = join(dir, 'mesh.obj');
    const args = ['mesh', expression, '--box', box.join(','), '--triangles', String(triangles), '-o', file];
    await promisify(execFile)(join(BIN_DIR, 'isomesh'), args, { timeout: 60000 });
    return readObj(readFileSync(file, 'utf8'));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

function readObj(text) {
  const positions = [];
  const triangles = [];
  for (const line of text.split('\n')) {
    const parts = line.trim().split(/\s+/);
    if (parts[0] === 'v') positions.push(parts.slice(1, 4).map(Number));
    if (parts[0] === 'f') triangles.push(parts.slice(1, 4).map((p) => Number(p.split('/')[0]) - 1));
  }
  return { positions, triangles };
}

/**
 * Compares a server mesh (SessionMesh.toIndexed(): positions on the session's quantization grid)
 * with a CLI mesh (exact positions): each CLI vertex must match one server vertex within
 * `tolerance` on every axis, and the triangles must be the same through that matching.
 * Returns a list of differences (empty when identical).
 */
export function compareMeshes(server, cli, tolerance) {
  const problems = [];
  const vertexCount = server.positions.length / 3;
  if (vertexCount !== cli.positions.length) problems.push(`vertices: server ${vertexCount}, cli ${cli.positions.length}`);
  if (server.indices.length / 3 !== cli.triangles.length) {
    problems.push(`triangles: server ${server.indices.length / 3}, cli ${cli.triangles.length}`);
  }
  if (problems.length > 0) return problems;

  const cell = (x) => Math.floor(x / tolerance);
  const grid = new Map();
  for (let v = 0; v < vertexCount; ++v) {
    const key = [0, 1, 2].map((a) => cell(server.positions[3 * v + a])).join(',');
    grid.set(key, [...(grid.get(key) ?? []), v]);
  }
  const match = cli.positions.map((p, index) => {
    const [cx, cy, cz] = p.map(cell);
    for (let dx = -1; dx <= 1; ++dx) {
      for (let dy = -1; dy <= 1; ++dy) {
        for (let dz = -1; dz <= 1; ++dz) {
          for (const v of grid.get(`${cx + dx},${cy + dy},${cz + dz}`) ?? []) {
            if ([0, 1, 2].every((a) => Math.abs(server.positions[3 * v + a] - p[a]) <= tolerance)) return v;
          }
        }
      }
    }
    problems.push(`cli vertex ${index} at ${p} has no server vertex within ${tolerance}`);
    return -1;
  });
  if (problems.length > 0) return problems.slice(0, 5);

  const serverTriangles = [];
  for (let t = 0; t < server.indices.length; t += 3) serverTriangles.push(rotated([...server.indices.subarray(t, t + 3)]));
  const cliTriangles = cli.triangles.map((t) => rotated(t.map((v) => match[v])));
  serverTriangles.sort(compareTriples);
  cliTriangles.sort(compareTriples);
  for (let t = 0; t < cliTriangles.length; ++t) {
    if (compareTriples(serverTriangles[t], cliTriangles[t]) !== 0) {
      problems.push(`triangle ${t}: server ${serverTriangles[t]}, cli ${cliTriangles[t]}`);
      break;
    }
  }
  return problems;
}

/** A raw WebSocket that collects JSON messages, for requests the client library would refuse. */
export async function rawSocket(server) {
  const socket = new WebSocket(server.wsUrl);
  const messages = [];
  const frames = [];
  socket.on('message', (data, isBinary) => {
    if (isBinary) frames.push(data);
    else messages.push(JSON.parse(data.toString()));
  });
  await new Promise((resolve, reject) => {
    socket.once('open', resolve);
    socket.once('error', reject);
  });
  return {
    socket,
    messages,
    frames,
    send(message) {
      socket.send(typeof message === 'string' ? message : JSON.stringify(message));
    },
    /** Resolves with the reply whose id is `id`. */
    async reply(id, timeoutMs = 20000) {
      await until(() => messages.some((m) => m.id === id), { timeoutMs, what: `reply ${id}` });
      return messages.find((m) => m.id === id);
    },
    close() {
      socket.close();
    },
  };
}

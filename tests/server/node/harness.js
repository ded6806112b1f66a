// What the integration tests share: a real isomesh-server on a free loopback port (--port 0; the
// port comes from its "listening" log line), clients of the isomesh-client library (clients/js)
// over the `ws` package with Google's draco3d decoder, the server's /metrics and /proc status, and
// the `isomesh mesh` CLI for reference meshes.
//
// Binaries come from build/bin, or from $ISOMESH_BIN_DIR (e.g. a developer's own build folder).

import assert from 'node:assert/strict';
import { spawn, execFile } from 'node:child_process';
import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';
import { promisify } from 'node:util';

import createDecoderModule from 'draco3d/draco_decoder_nodejs.js';
import WebSocket from 'ws';

import { connect, decodeFrame, DracoMeshDecoder, Outcome, SessionMesh } from '../../../clients/js/src/index.js';
import { compileSurface, valueAndGradient } from './surface.js';

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
 * `prefix`: a command the server runs under (e.g. ['prlimit', '--nofile=64'] or
 * ['taskset', '-c', '0']); `env`: variables added to the server's environment; `bare`: no default
 * arguments (configured by `env` alone).
 */
export function startServer(args = [], { timeoutMs = 20000, prefix = [], env = {}, bare = false } = {}) {
  const defaults = bare ? [] : ['--bind', '127.0.0.1', '--port', '0', '--threads', '2', '--web-root', '', '--store', 'none'];
  const fullArgs = [];
  for (let i = 0; i < defaults.length; i += 2) {
    if (!args.includes(defaults[i])) fullArgs.push(defaults[i], defaults[i + 1]);
  }
  fullArgs.push(...args);
  const command = [...prefix, join(BIN_DIR, 'isomesh-server'), ...fullArgs];
  const child = spawn(command[0], command.slice(1), { stdio: ['ignore', 'ignore', 'pipe'], env: { ...process.env, ...env } });
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

/**
 * An isomesh-client connection to `server` whose every session is checked after every frame
 * (checkFrames below); close() throws an AssertionError listing what the checks found.
 * `options.knownDefects`: checks not to count, see meshProblems.
 */
export async function client(server, options = {}) {
  const { knownDefects = [], ...connectOptions } = options;
  const connection = await connect(server.wsUrl, { decoder: await decoder(), WebSocket, ...connectOptions });
  const checker = new FrameChecker(knownDefects);
  const watched = new WeakSet();
  for (const method of ['create', 'subscribe']) {
    const original = connection[method].bind(connection);
    connection[method] = async (...args) => {
      const session = await original(...args);
      if (!watched.has(session)) {
        watched.add(session);
        checker.watch(session);
      }
      return session;
    };
  }
  const close = connection.close.bind(connection);
  connection.close = () => {
    close();
    checker.assertValid();
  };
  connection.checker = checker;
  return connection;
}

// ---- the validity of every frame ----------------------------------------------------------------

/** The step of a session's 14-bit quantization grid for `box` (protocol/mesh_codec.h, for_box). */
export function gridStep(box) {
  const extent = Math.max(box[1] - box[0], box[3] - box[2], box[5] - box[4]);
  return (extent * (1 + 2 / 64)) / (2 ** 14 - 1);
}

const surfaces = new Map();
function surfaceOf(expression) {
  if (!surfaces.has(expression)) surfaces.set(expression, compileSurface(expression));
  return surfaces.get(expression);
}

/** The sign-carrying slope of f at `c` along the direction `n` (central difference, 2 values). */
function slopeAlong(f, c, n, parameters, h = 1e-6) {
  const length = Math.hypot(...n);
  const d = n.map((x) => (h * x) / length);
  return f(c[0] + d[0], c[1] + d[1], c[2] + d[2], parameters) - f(c[0] - d[0], c[1] - d[1], c[2] - d[2], parameters);
}

/**
 * Checks a session's mesh (a SessionMesh of the client library: triangle slots with their corners'
 * vertex ids and positions, and the live vertices) after every frame, as a mesh of the surface
 * f = 0 in the box of the frame's function version (issue 10). Problems:
 *   zero_area     a triangle with a repeated vertex or no area
 *   open          an edge used by one triangle, not on the box's boundary (a hole)
 *   non_manifold  a directed edge used twice (a fold, or inconsistent orientation)
 *   reversed      a triangle facing away from f > 0 (its normal against the gradient at its centre and at two corners or more)
 *   off_surface   a vertex further than two grid steps from the surface (|f| / |grad f|)
 * The edges are checked over the whole mesh after every frame; triangles and vertices where the
 * frame added them, or all of them after a keyframe and after the first frame of a function
 * version. Without an expression (a .vm session) only the first three are checked.
 */
export class CheckedMesh {
  constructor(mesh) {
    this.mesh = mesh;
    this.version = 0;
  }

  /** The problems after `frame` (already applied to the mesh), as a mesh of `state`. */
  check(frame, state, skip = []) {
    const full = frame.header.kind === 'keyframe' || frame.header.functionVersion !== this.version;
    this.version = frame.header.functionVersion;
    const problems = new Problems();
    const f = state.expression === undefined ? null : surfaceOf(state.expression);
    const parameters = state.parameters ?? {};
    if (full) this.#checkAll(problems, f, parameters, state.box);
    else if (frame.mesh) this.#checkAdded(problems, f, parameters, state.box, frame.mesh);
    this.#checkEdges(problems, state.box);
    return problems.list().filter((p) => !skip.includes(p.kind));
  }

  #checkAll(problems, f, parameters, box) {
    const { slots, vertices } = this.mesh;
    for (let t = 0; t < slots.count; ++t) checkTriangle(problems, f, parameters, slots.vertexIds, 3 * t, slots.positions, 9 * t);
    if (!f) return;
    for (const [id, row] of vertices.rowOf) checkVertex(problems, f, parameters, box, id, vertices.positions, 3 * row);
  }

  #checkAdded(problems, f, parameters, box, payload) {
    const { faces, globalIds, positions } = payload;
    const ids = new Uint32Array(3);
    const corners = new Float32Array(9);
    for (let t = 0; t < faces.length / 3; ++t) {
      for (let k = 0; k < 3; ++k) {
        const point = faces[3 * t + k];
        ids[k] = globalIds[point];
        corners.set(positions.subarray(3 * point, 3 * point + 3), 3 * k);
      }
      checkTriangle(problems, f, parameters, ids, 0, corners, 0);
    }
    if (!f) return;
    for (let point = 0; point < globalIds.length; ++point) checkVertex(problems, f, parameters, box, globalIds[point], positions, 3 * point);
  }

  /** Every directed edge once, and its opposite once unless it lies on the box's boundary. */
  #checkEdges(problems, box) {
    const { slots, vertices } = this.mesh;
    const ids = slots.vertexIds;
    const edges = new EdgeTable(3 * slots.count);
    for (let c = 0; c < 3 * slots.count; c += 3) {
      edges.add(ids[c], ids[c + 1]);
      edges.add(ids[c + 1], ids[c + 2]);
      edges.add(ids[c + 2], ids[c]);
    }
    const step = gridStep(box);
    const onBoundary = (id) => {
      const row = vertices.rowOf.get(id);
      const q = vertices.positions.subarray(3 * row, 3 * row + 3);
      return [0, 1, 2].some((a) => Math.abs(q[a] - box[2 * a]) <= step || Math.abs(q[a] - box[2 * a + 1]) <= step);
    };
    edges.forEach((a, b, uses) => {
      if (uses > 1) problems.note('non_manifold', `edge ${a}-${b} used ${uses} times`);
      else if (edges.uses(b, a) === 0 && !(onBoundary(a) && onBoundary(b))) problems.note('open', `edge ${a}-${b}`);
    });
  }
}

/** The triangle of vertex ids ids[i..i+3) with corners corners[c..c+9): area and orientation. */
function checkTriangle(problems, f, parameters, ids, i, corners, c) {
  const a = ids[i];
  const b = ids[i + 1];
  const d = ids[i + 2];
  const u0 = corners[c + 3] - corners[c];
  const u1 = corners[c + 4] - corners[c + 1];
  const u2 = corners[c + 5] - corners[c + 2];
  const w0 = corners[c + 6] - corners[c];
  const w1 = corners[c + 7] - corners[c + 1];
  const w2 = corners[c + 8] - corners[c + 2];
  const n = [u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0];
  if (a === b || b === d || a === d || (n[0] === 0 && n[1] === 0 && n[2] === 0)) {
    problems.note('zero_area', `triangle of vertices ${a}, ${b}, ${d}`);
    return;
  }
  if (!f) return;
  const centre = [0, 1, 2].map((k) => (corners[c + k] + corners[c + 3 + k] + corners[c + 6 + k]) / 3);
  if (slopeAlong(f, centre, n, parameters) >= 0) return;
  // Against f's gradient at the centre and at two corners or more. The corners alone are on the
  // surface: a coarse first mesh's triangle (7 units across in the blobby cube's box) may span a
  // fold of f, and its centre see a gradient the surface never has there.
  const corner = (k) => [corners[c + 3 * k], corners[c + 3 * k + 1], corners[c + 3 * k + 2]];
  const against = [0, 1, 2].filter((k) => slopeAlong(f, corner(k), n, parameters) < 0).length;
  if (against >= 2) problems.note('reversed', `triangle at ${centre.map((x) => x.toFixed(3))}`);
}

/** Vertex `id` at positions[p..p+3): within two grid steps of the surface. */
function checkVertex(problems, f, parameters, box, id, positions, p) {
  const { value, gradient } = valueAndGradient(f, positions[p], positions[p + 1], positions[p + 2], parameters);
  const slope = Math.hypot(gradient[0], gradient[1], gradient[2]);
  const distance = Math.abs(value) / slope;
  if (slope > 1e-9 && distance > 2 * gridStep(box)) {
    const at = [0, 1, 2].map((k) => positions[p + k].toFixed(4));
    problems.note('off_surface', `vertex ${id} at ${at}, ${distance.toExponential(2)} away`);
  }
}

/**
 * Directed edges (pairs of uint32 vertex ids) and their uses: an open-addressing hash table of
 * (from, to, uses) triples in one array, hashed by the first vertex so that the edges of nearby
 * triangles stay near in memory (checking 100,000 triangles is memory-bound).
 */
class EdgeTable {
  constructor(capacity) {
    let size = 16;
    while (size < 2 * capacity) size *= 2;
    this.mask = size - 1;
    this.slots = new Uint32Array(3 * size); // from, to, uses (0: empty)
  }

  #slot(a, b) {
    const s = this.slots;
    let i = ((a << 3) + (b & 7)) & this.mask;
    while (s[3 * i + 2] !== 0 && (s[3 * i] !== a || s[3 * i + 1] !== b)) i = (i + 1) & this.mask;
    return 3 * i;
  }

  add(a, b) {
    const i = this.#slot(a, b);
    this.slots[i] = a;
    this.slots[i + 1] = b;
    ++this.slots[i + 2];
  }

  uses(a, b) {
    return this.slots[this.#slot(a, b) + 2];
  }

  forEach(visit) {
    const s = this.slots;
    for (let i = 0; i < s.length; i += 3) if (s[i + 2] > 0) visit(s[i], s[i + 1], s[i + 2]);
  }
}

/** Problems by kind: how many and one example. */
class Problems {
  constructor() {
    this.found = new Map();
  }

  note(kind, example) {
    if (!this.found.has(kind)) this.found.set(kind, { kind, count: 0, example });
    ++this.found.get(kind).count;
  }

  list() {
    return [...this.found.values()];
  }
}

/**
 * Checks meshes after every frame (CheckedMesh): for each session, the function of each version
 * (from the created, updated and subscribed messages) and the mesh its frames build.
 * `knownDefects`: problem kinds not counted (each use names the core defect behind it).
 */
export class FrameChecker {
  constructor(knownDefects = []) {
    this.knownDefects = knownDefects;
    this.problems = [];
    this.frames = 0;
    this.sessions = new Map(); // session id -> {checked, versions}
  }

  #follow(session, mesh = new SessionMesh()) {
    if (!this.sessions.has(session)) this.sessions.set(session, { checked: new CheckedMesh(mesh), versions: new Map() });
    return this.sessions.get(session);
  }

  /** A control message: created, updated and subscribed announce versions. */
  message(message) {
    if (['created', 'updated', 'subscribed'].includes(message.type)) this.#follow(message.session).versions.set(message.version, message);
  }

  /** Follows a Session of the client library (it applies the frames; they are checked after). */
  watch(session) {
    this.sessions.delete(session.id); // a new subscription brings a new mesh
    const followed = this.#follow(session.id, session.mesh);
    if (session.state) followed.versions.set(session.state.version, session.state);
    session.on('state', (state) => followed.versions.set(state.version, state));
    const check = (frame) => this.#check(followed, frame);
    session.on('keyframe', check);
    session.on('delta', check);
  }

  /** A decoded frame of a raw connection: applied to the session's own mesh, then checked. */
  frame(frame) {
    const followed = this.#follow(frame.header.session);
    if (followed.checked.mesh.apply(frame) === Outcome.applied) this.#check(followed, frame);
  }

  #check(followed, frame) {
    const h = frame.header;
    ++this.frames;
    let state = followed.versions.get(h.functionVersion);
    if (!state) {
      // A late subscriber's keyframe may hold a version older than the one `subscribed` named
      // (PROTOCOL.md 3.2: the mesh is still moving to it): its surface is unknown here, so only
      // the mesh itself is checked. A frame of a newer version must have been announced.
      const known = Math.min(...followed.versions.keys());
      if (!(h.kind === 'keyframe' && h.functionVersion < known)) {
        this.problems.push(`frame ${h.sequence} of version ${h.functionVersion}, never announced`);
        return;
      }
      state = { box: followed.versions.get(known).box };
    }
    for (const p of followed.checked.check(frame, state, this.knownDefects)) {
      this.problems.push(`${state.expression ?? '(vm)'} v${h.functionVersion} frame ${h.sequence}: ${p.count} ${p.kind} (e.g. ${p.example})`);
    }
  }

  assertValid() {
    if (this.problems.length > 0) {
      const shown = this.problems.slice(0, 8).join('\n  ');
      throw new assert.AssertionError({ message: `${this.problems.length} invalid frames of ${this.frames}:\n  ${shown}` });
    }
  }
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

/**
 * A raw WebSocket that collects JSON messages, for requests the client library would refuse. Its
 * frames are applied and checked too (FrameChecker): close() throws when one was invalid.
 */
export async function rawSocket(server, { knownDefects = [], headers } = {}) {
  const draco = await decoder();
  const socket = new WebSocket(server.wsUrl, { headers });
  const messages = [];
  const frames = [];
  const checker = new FrameChecker(knownDefects);
  socket.on('message', (data, isBinary) => {
    if (!isBinary) {
      const message = JSON.parse(data.toString());
      messages.push(message);
      checker.message(message);
      return;
    }
    frames.push(data);
    checker.frame(decodeFrame(new Uint8Array(data.buffer, data.byteOffset, data.byteLength), draco));
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
    checker,
    close() {
      socket.close();
      checker.assertValid();
    },
  };
}

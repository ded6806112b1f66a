// The client's request/reply matching, events and gap handling, against an in-process fake
// WebSocket playing the server (frames with stand-in payloads, see support.js).

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { connect, routeOf } from '../src/client.js';
import { FakeMeshDecoder, SESSION, buildFrame, vertex } from './support.js';

class FakeSocket {
  static last = null;

  constructor(url) {
    this.url = url;
    this.sent = [];
    this.binaryType = 'blob';
    FakeSocket.last = this;
    queueMicrotask(() => this.onopen?.());
  }

  send(text) {
    this.sent.push(JSON.parse(text));
  }

  close(code = 1000, reason = '') {
    queueMicrotask(() => this.onclose?.({ code, reason }));
  }

  /** The server's side. */
  reply(message) {
    this.onmessage({ data: JSON.stringify({ v: 1, ...message }) });
  }

  frame(options) {
    const bytes = buildFrame(options);
    this.onmessage({ data: bytes.buffer });
  }

  lastSent() {
    return this.sent[this.sent.length - 1];
  }
}

/** Resolves when `predicate()` holds (polled every millisecond, for at most 2 s). */
async function until(predicate) {
  const end = Date.now() + 2000;
  while (!predicate()) {
    if (Date.now() > end) throw new Error('timed out');
    await new Promise((resolve) => setTimeout(resolve, 1));
  }
}

const state = { version: 1, expression: 'x^2+y^2+z^2=a', parameters: { a: 1 }, box: [-2, 2, -2, 2, -2, 2], constraints: { triangles: 100, max_error: 0, error_measure: 'epsilon4' } };
const square = { vertices: [1, 2, 3, 4].map((id) => vertex(id)), triangles: [[1, 2, 3], [1, 3, 4]] };

async function connected(options = {}) {
  const client = await connect('ws://127.0.0.1:1/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), ...options });
  return { client, socket: FakeSocket.last };
}

async function created(client, socket) {
  const pending = client.create({ expression: 'x^2+y^2+z^2=a', parameters: { a: 1 }, box: state.box });
  const request = socket.lastSent();
  socket.reply({ type: 'created', id: request.id, session: SESSION, ...state });
  return pending;
}

test('connect needs a WebSocket and a decoder', async () => {
  await assert.rejects(connect('ws://x', { WebSocket: FakeSocket }), /decoder/);
  await assert.rejects(connect('ws://x', { WebSocket: null, decoder: new FakeMeshDecoder() }), /WebSocket/);
});

test('connect speaks protocol version 1 when asked (options.protocolVersion), and only 1 or 2', async () => {
  const { client, socket } = await connected({ protocolVersion: 1 });
  await created(client, socket);
  assert.equal(socket.sent[0].v, 1);
  await assert.rejects(connected({ protocolVersion: 3 }), /protocolVersion/);
});

test('create sends a versioned request and resolves with the session on its reply', async () => {
  const { client, socket } = await connected();
  assert.equal(socket.binaryType, 'arraybuffer');
  const session = await created(client, socket);
  assert.deepEqual(socket.sent[0], { v: 2, type: 'create', id: 1, expression: 'x^2+y^2+z^2=a', parameters: { a: 1 }, box: state.box });
  assert.equal(session.id, SESSION);
  assert.deepEqual(session.state.parameters, { a: 1 });
  assert.equal(client.sessions.get(SESSION), session);
});

test('a keyframe read in the same turn as its created reply is not lost', async () => {
  const { client, socket } = await connected();
  const pending = client.create({ expression: 'x^2+y^2+z^2=a', parameters: { a: 1 }, box: state.box });
  socket.reply({ type: 'created', id: socket.lastSent().id, session: SESSION, ...state });
  socket.frame({ kind: 'keyframe', sequence: 0, triangleIds: [1, 2], mesh: square }); // no await between
  const session = await pending;
  assert.equal(session.mesh.triangleCount, 2);
});

test('frames reach their session: keyframe and delta events, first mesh time, converged', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const events = [];
  for (const name of ['keyframe', 'delta', 'firstMesh', 'progress', 'converged']) session.on(name, () => events.push(name));
  socket.frame({ kind: 'keyframe', sequence: 0, triangleIds: [1, 2], mesh: square });
  socket.frame({ sequence: 1, removed: [2] });
  socket.reply({ type: 'progress', session: SESSION, version: 1, sequence: 1, triangles: 1, error_max: 0.5, error_total: 1, splits_per_second: 10 });
  assert.equal(session.converged, false);
  socket.reply({ type: 'converged', session: SESSION, version: 1, sequence: 1, triangles: 1, error_max: 0, error_total: 0, splits: 0, merges: 0, first_mesh_ms: 1, total_ms: 2 });
  assert.deepEqual(events, ['keyframe', 'firstMesh', 'delta', 'progress', 'converged']);
  assert.equal(session.mesh.triangleCount, 1);
  assert.equal(session.converged, true);
  assert.ok(session.stats.firstMeshMs >= 0);
  assert.equal(session.stats.frames, 2);
  assert.ok(client.bytesReceived > 0);
});

test('an error reply rejects the request with its code and column; the session keeps its state', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const pending = session.update({ expression: 'x^2+(y' });
  assert.equal(session.converged, false, 'an update is in flight');
  socket.reply({ type: 'error', id: socket.lastSent().id, session: SESSION, code: 'bad_expression', message: 'expected ) at column 7', column: 7 });
  await assert.rejects(pending, (e) => e.code === 'bad_expression' && e.column === 7 && /column 7/.test(e.message));
  assert.equal(session.state.version, 1);
});

test('update merges into the state the reply reports', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const pending = session.update({ parameters: { a: 2 } });
  assert.deepEqual(socket.lastSent(), { v: 2, type: 'update', id: 2, session: SESSION, parameters: { a: 2 } });
  socket.reply({ type: 'updated', id: 2, session: SESSION, ...state, version: 2, parameters: { a: 2 } });
  assert.deepEqual((await pending).parameters, { a: 2 });
  assert.equal(session.state.version, 2);
});

test('a sequence gap sends one resync; the next keyframe restores the mesh', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const resyncs = [];
  session.on('resync', (e) => resyncs.push(e.reason));
  socket.frame({ kind: 'keyframe', sequence: 0, triangleIds: [1, 2], mesh: square });
  socket.frame({ sequence: 2, removed: [2] });
  socket.frame({ sequence: 3, removed: [1] });
  assert.deepEqual(resyncs, ['gap']);
  const resync = socket.sent.filter((m) => m.type === 'resync');
  assert.equal(resync.length, 1);
  assert.equal(resync[0].session, SESSION);
  socket.reply({ type: 'ack', id: resync[0].id, request: 'resync', session: SESSION });
  socket.frame({ kind: 'keyframe', flags: 2, sequence: 3, triangleIds: [1], mesh: { vertices: square.vertices.slice(0, 3), triangles: [[1, 2, 3]] } });
  assert.equal(session.mesh.synchronized, true);
  assert.equal(session.mesh.triangleCount, 1);
  socket.frame({ sequence: 4, removed: [1] });
  assert.equal(session.mesh.triangleCount, 0);
});

test('a frame that does not decode makes its session resync', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const errors = [];
  session.on('error', (e) => errors.push(e.code));
  const bytes = buildFrame({ sequence: 1, removed: [1, 2], override: { removedCount: 3 } });
  socket.onmessage({ data: bytes.buffer });
  assert.deepEqual(errors, ['bad_frame']);
  assert.equal(socket.lastSent().type, 'resync');
});

test('errors that answer no request go to the session or the client', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  const seen = [];
  session.on('error', (e) => seen.push(['session', e.code]));
  client.on('error', (e) => seen.push(['client', e.code]));
  socket.reply({ type: 'error', session: SESSION, code: 'eval_timeout', message: 'too slow' });
  socket.reply({ type: 'error', code: 'bad_json', message: 'not JSON' });
  socket.onmessage({ data: '{"v":3,"type":"pong"}' });
  socket.reply({ type: 'error', code: 'some_future_code', message: 'new in a later server' });
  assert.deepEqual(seen, [['session', 'eval_timeout'], ['client', 'bad_json'], ['client', 'unsupported_version'], ['client', 'internal']]);
});

test('closed sessions leave the client; a closed connection rejects pending requests', async () => {
  const { client, socket } = await connected();
  const session = await created(client, socket);
  let reason = null;
  session.on('closed', (m) => (reason = m.reason));
  socket.reply({ type: 'closed', session: SESSION, reason: 'expired' });
  assert.equal(reason, 'expired');
  assert.equal(client.sessions.size, 0);
  const ping = client.ping();
  client.close();
  await assert.rejects(ping, (e) => e.code === 'closed');
  await assert.rejects(client.ping(), (e) => e.code === 'closed');
});

test('requests time out when no reply comes', async () => {
  const client = await connect('ws://x', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), requestTimeoutMs: 10 });
  await assert.rejects(client.ping(), (e) => e.code === 'timeout');
});

test('bad arguments fail before anything is sent', async () => {
  const { client, socket } = await connected();
  await assert.rejects(client.create({ expression: 'x=1', box: [0, 1, 0, 1, 0] }), /box/);
  await assert.rejects(client.create({ expression: 'x=1', parameters: { a: NaN } }), /finite/);
  await assert.rejects(client.create({ expression: 'x=1', constraints: { triangles: 0.5 } }), /triangles/);
  assert.equal(socket.sent.length, 0);
});

test('deferred frames wait for drainFrames and apply in order', async () => {
  const client = await connect('ws://x', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), deferFrames: true });
  const socket = FakeSocket.last;
  const session = await created(client, socket);
  socket.frame({ kind: 'keyframe', sequence: 0, triangleIds: [1, 2], mesh: square });
  socket.frame({ sequence: 1, removed: [2] });
  socket.frame({ sequence: 2, removed: [1] });
  assert.equal(session.mesh.triangleCount, 0, 'nothing applied yet');
  assert.equal(client.pendingFrames, 3);
  assert.equal(client.drainFrames(0), 2, 'a deadline in the past still applies one frame');
  assert.equal(session.mesh.triangleCount, 2);
  assert.equal(client.drainFrames(), 0);
  assert.equal(session.mesh.triangleCount, 0);
  assert.equal(session.mesh.sequence, 2);
});

test('the URL carries the route; sessions have their route', async () => {
  const client = await connect('ws://127.0.0.1:1/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), route: '0A1B2C3D' });
  assert.equal(FakeSocket.last.url, 'ws://127.0.0.1:1/ws?route=0a1b2c3d');
  assert.equal(client.route, '0a1b2c3d');
  assert.equal(routeOf('0a1b2c3d445566778899aabbccddeeff'), '0a1b2c3d');
  const random = await connect('ws://h/ws?x=1', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder() });
  assert.match(FakeSocket.last.url, /^ws:\/\/h\/ws\?x=1&route=[0-9a-f]{8}$/);
  assert.equal(random.route.length, 8);
  await connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), route: null });
  assert.equal(FakeSocket.last.url, 'ws://h/ws');
  await assert.rejects(connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), route: 'xyz' }), /8 hex digits/);
});

test('a dropped connection reconnects, resubscribes and sends again the update in flight; a create in flight rejects', async () => {
  const client = await connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), reconnectDelaysMs: [1] });
  const first = FakeSocket.last;
  const session = await created(client, first);
  first.frame({ kind: 'keyframe', sequence: 0, triangleIds: [1, 2], mesh: square });
  const update = session.update({ parameters: { a: 2 } });
  const create = client.create({ expression: 'x=0', box: state.box });
  const events = [];
  client.on('disconnected', () => events.push('disconnected'));
  client.on('reconnected', () => events.push('reconnected'));
  first.onclose({ code: 1006, reason: '' }); // the server is gone
  await assert.rejects(create, (e) => e.code === 'closed');
  assert.equal(client.connected, false);
  await until(() => FakeSocket.last !== first && client.connected);
  const second = FakeSocket.last;
  assert.equal(second.url, first.url, 'the same route');
  assert.deepEqual(events, ['disconnected', 'reconnected']);
  assert.deepEqual(second.sent.map((m) => [m.type, m.session]), [['subscribe', SESSION], ['update', SESSION]]);
  assert.deepEqual(second.sent[1].parameters, { a: 2 });
  second.reply({ type: 'subscribed', id: second.sent[0].id, session: SESSION, ...state });
  second.reply({ type: 'updated', id: second.sent[1].id, session: SESSION, ...state, version: 2, parameters: { a: 2 } });
  assert.equal((await update).version, 2);
  second.frame({ kind: 'keyframe', sequence: 0, triangleIds: [7], mesh: { vertices: square.vertices.slice(0, 3), triangles: [[1, 2, 3]] } });
  assert.equal(session.mesh.triangleCount, 1, 'the keyframe of the rebuilt session applies');
  assert.ok(session.stats.firstMeshMs >= 0, 'timed from the new subscribe');
  assert.equal(client.sessions.get(SESSION), session);
  client.close();
});

test('closed with reason moved reconnects; a session that cannot be resubscribed is lost', async () => {
  const client = await connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), reconnectDelaysMs: [1] });
  const first = FakeSocket.last;
  const session = await created(client, first);
  const seen = [];
  session.on('moved', () => seen.push('moved'));
  session.on('closed', (m) => seen.push(`closed ${m.reason}`));
  first.reply({ type: 'closed', session: SESSION, reason: 'moved' });
  await until(() => FakeSocket.last !== first && client.connected);
  const second = FakeSocket.last;
  assert.equal(second.sent[0].type, 'subscribe');
  second.reply({ type: 'error', id: second.sent[0].id, session: SESSION, code: 'unknown_session', message: 'gone' });
  await until(() => seen.length === 2);
  assert.deepEqual(seen, ['moved', 'closed lost']);
  assert.equal(client.sessions.size, 0);
  client.close();
});

/** A server that is down: each socket fails as browsers and `ws` report it, `error` then `close`. */
class RefusedSocket extends FakeSocket {
  static opened = 0;
  static refusing = true;

  constructor(url) {
    super(url);
    ++RefusedSocket.opened;
    if (!RefusedSocket.refusing) return;
    Object.defineProperty(this, 'onopen', { set: () => {}, get: () => undefined });
    queueMicrotask(() => {
      this.onerror?.({});
      this.onclose?.({ code: 1006, reason: '' });
    });
  }
}

test('a server that stays down is tried one attempt at a time (error then close count once)', async (t) => {
  RefusedSocket.refusing = false;
  const client = await connect('ws://h/ws', { WebSocket: RefusedSocket, decoder: new FakeMeshDecoder(), reconnectDelaysMs: [2], maxReconnectAttempts: 1000 });
  const first = FakeSocket.last;
  // Mocked timers: each 3 ms tick fires the pending attempt (2 ms ± 20 %), whose socket fails at
  // once; one next attempt per failure gives one attempt per tick, two would double every tick.
  t.mock.timers.enable({ apis: ['setTimeout'] });
  const settle = () => new Promise((resolve) => setImmediate(resolve));
  RefusedSocket.refusing = true;
  RefusedSocket.opened = 0;
  first.onclose({ code: 1006, reason: '' });
  for (let tick = 1; tick <= 10; ++tick) {
    t.mock.timers.tick(3);
    await settle();
    assert.equal(RefusedSocket.opened, tick, `one attempt per delay, not ${RefusedSocket.opened} after ${tick}`);
  }
  RefusedSocket.refusing = false;
  t.mock.timers.tick(3);
  await settle();
  assert.ok(client.connected);
  assert.equal(client.reconnects, 1);
  const opened = RefusedSocket.opened;
  t.mock.timers.tick(100);
  await settle();
  assert.equal(RefusedSocket.opened, opened, 'no attempt left running once connected');
  client.close();
});

test('requests made while disconnected wait for the new connection; close() ends it all', async () => {
  const client = await connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), reconnectDelaysMs: [50] });
  const first = FakeSocket.last;
  first.onclose({ code: 1006, reason: '' });
  const ping = client.ping();
  await until(() => FakeSocket.last !== first && client.connected);
  assert.equal(FakeSocket.last.sent[0].type, 'ping');
  FakeSocket.last.reply({ type: 'pong', id: FakeSocket.last.sent[0].id, time_us: 1 });
  assert.equal((await ping).serverTimeUs, 1);
  let closed = false;
  client.on('close', () => (closed = true));
  client.close();
  await until(() => closed);
  assert.equal(client.closed, true);
  await assert.rejects(client.ping(), (e) => e.code === 'closed');
});

test('after a reconnection the rebuilt session counts its sequences from 0: its converged waits for its own keyframe, frames queued before the drop are dropped', async () => {
  const client = await connect('ws://h/ws', { WebSocket: FakeSocket, decoder: new FakeMeshDecoder(), reconnectDelaysMs: [1], deferFrames: true });
  const first = FakeSocket.last;
  const session = await created(client, first);
  for (let s = 0; s <= 16; ++s) first.frame({ kind: 'keyframe', sequence: s, triangleIds: [1, 2], mesh: square });
  client.drainFrames();
  first.reply({ type: 'converged', session: SESSION, version: 1, sequence: 16, triangles: 2 });
  assert.ok(session.converged);
  first.frame({ kind: 'keyframe', sequence: 17, triangleIds: [1, 2], mesh: square }); // queued, then the server dies
  first.onclose({ code: 1006, reason: '' });
  assert.equal(session.converged, false, 'not known to be final while disconnected');
  await until(() => FakeSocket.last !== first && client.connected);
  const second = FakeSocket.last;
  second.reply({ type: 'subscribed', id: second.sent[0].id, session: SESSION, ...state });
  second.frame({ kind: 'keyframe', sequence: 0, triangleIds: [7], mesh: { vertices: square.vertices.slice(0, 3), triangles: [[1, 2, 3]] } });
  second.reply({ type: 'converged', session: SESSION, version: 1, sequence: 15, triangles: 1 });
  assert.equal(session.converged, false, 'the converged of the rebuilt session names a frame not applied yet');
  assert.equal(session.mesh.triangleCount, 2, 'the mesh on hand stays shown meanwhile');
  assert.equal(client.drainFrames(), 0, "the old connection's queued keyframe is gone");
  assert.equal(session.mesh.triangleCount, 1, "the rebuilt session's keyframe applied");
  assert.equal(session.converged, false, 'sequence 0 of 15');
  client.close();
});

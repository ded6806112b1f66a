// Integration tests of isomesh-server: the real binary on a loopback port, real WebSocket clients
// (isomesh-client over `ws`, frames decoded by draco3d), every frame applied.
//
//   cd tests/server/node && npm ci --no-audit --no-fund && node --test
//
// Each test starts its own server (so that limits and timeouts can differ) and stops it.

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { get as httpGet } from 'node:http';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';

import {
  canonicalTriangles,
  cliMesh,
  client,
  compareMeshes,
  converged,
  convergedAt,
  positionTriangles,
  rawSocket,
  startServer,
  until,
  watertight,
} from './harness.js';

const BOX = [-3, 3, -3, 3, -3, 3];
// The step of the session's 14-bit quantization grid for BOX (protocol/mesh_codec.h, for_box).
const GRID_STEP = (6 * (1 + 2 / 64)) / (2 ** 14 - 1);

const GALLERY = [
  { name: 'sphere |r| = 2 (the thesis)', expression: 'sqrt(x^2+y^2+z^2)=2' },
  { name: 'wobbly sphere', expression: 'x^2+y^2+z^2+2cos(2x)=5' },
  { name: 'torus', expression: '(sqrt(x^2+y^2)-1.8)^2+z^2=0.5' },
  { name: 'tanglecube (genus 5)', expression: 'x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0' },
  { name: 'oblate spheroid (the thesis)', expression: '10x^2+y^2+z^2=5' },
];

/** The status of GET `path` sent as is. */
function rawGetStatus(port, path) {
  return new Promise((resolve, reject) => {
    httpGet({ host: '127.0.0.1', port, path }, (response) => {
      response.resume();
      resolve(response.statusCode);
    }).on('error', reject);
  });
}

async function withServer(args, body) {
  const server = await startServer(args);
  try {
    return await body(server);
  } finally {
    const { code } = await server.stop();
    assert.equal(code, 0, `server exit code; log:\n${server.log.slice(-20).join('\n')}`);
  }
}

describe('meshes', () => {
  let server;
  before(async () => {
    server = await startServer();
  });
  after(async () => {
    assert.equal((await server.stop()).code, 0);
  });

  test('frames of a new session are numbered 0, 1, 2, ... from its first keyframe', async () => {
    const raw = await rawSocket(server);
    try {
      raw.send({ v: 1, type: 'create', id: 1, expression: 'x^2+y^2+z^2=4', box: BOX, constraints: { triangles: 2000 } });
      assert.equal((await raw.reply(1)).type, 'created');
      await until(() => raw.messages.some((m) => m.type === 'converged'), { what: 'converged' });
      const headers = raw.frames.map((f) => ({ kind: f.readUInt8(5), sequence: Number(f.readBigUInt64LE(24)) }));
      assert.deepEqual(headers[0], { kind: 1, sequence: 0 }, 'the first frame is keyframe 0');
      headers.forEach((h, i) => assert.equal(h.sequence, i));
    } finally {
      raw.close();
    }
  });

  for (const surface of GALLERY) {
    test(`${surface.name}: watertight and identical to isomesh mesh`, async () => {
      const triangles = 4000;
      const connection = await client(server);
      try {
        const session = await connection.create({ expression: surface.expression, box: BOX, constraints: { triangles } });
        await converged(session);
        assert.equal(session.stats.resyncs, 0);
        const mesh = session.mesh.toIndexed();
        assert.ok(watertight(mesh.indices), 'every edge shared by two triangles, oriented');
        assert.equal(session.lastConverged.triangles, mesh.indices.length / 3);
        const reference = await cliMesh(surface.expression, { box: BOX, triangles });
        assert.deepEqual(compareMeshes(mesh, reference, GRID_STEP), []);
      } finally {
        connection.close();
      }
    });
  }

  test('a version-1 and a version-2 client of one session end with the same triangles at bit-equal positions, through a slider move', async () => {
    // client() checks every frame of both after it is applied (FrameChecker): version 2's deltas
    // are decoded against the mesh the library holds (PROTOCOL.md 4.5).
    const [v1, v2] = await Promise.all([client(server, { protocolVersion: 1 }), client(server, { protocolVersion: 2 })]);
    try {
      const first = await v2.create({ expression: 'x^2+y^2+z^2+cos(3x)=a', parameters: { a: 4 }, box: BOX, constraints: { triangles: 20000 } });
      const other = await v1.subscribe(first.id);
      await Promise.all([converged(first), converged(other)]);
      assert.deepEqual(positionTriangles(first.mesh), positionTriangles(other.mesh));
      await first.update({ parameters: { a: 4.5 } });
      await Promise.all([convergedAt(first, first.state.version), convergedAt(other, first.state.version)]);
      assert.deepEqual(positionTriangles(first.mesh), positionTriangles(other.mesh));
      assert.equal(first.stats.resyncs + other.stats.resyncs, 0);
      assert.ok(first.stats.deltas > 0, 'version-2 deltas were applied');
      // The point of version 2: fewer bytes for the same mesh.
      assert.ok(first.stats.bytes < other.stats.bytes, `version 2: ${first.stats.bytes} bytes, version 1: ${other.stats.bytes}`);
    } finally {
      v1.close();
      v2.close();
    }
  });

  test('a slider drag: frames on their version\'s surface, the same mesh for every client, and the last version\'s mesh is a fresh session\'s', async () => {
    // Updates 30 ms apart, not awaited (a user dragging a slider); a version-1 client subscribes
    // mid-drag (its keyframe comes from the version-1 mirror, which followed without frames). The
    // values stay within one move's reach, so the last version's vertices always move.
    const [a, b, c, d] = await Promise.all([client(server), client(server), client(server, { protocolVersion: 1 }), client(server)]);
    try {
      const definition = { expression: 'x^2+y^2+z^2=a', box: BOX, constraints: { triangles: 8000 } };
      const dragged = await a.create({ ...definition, parameters: { a: 4 } });
      const watcher = await b.subscribe(dragged.view);
      await Promise.all([converged(dragged), converged(watcher)]);
      let moved = 0;
      dragged.on('delta', (frame) => (moved += frame.moved?.length ?? 0));
      const updates = [];
      let late;
      for (let i = 1; i <= 12; ++i) {
        updates.push(dragged.update({ parameters: { a: 4 + 0.05 * i } }));
        if (i === 4) late = await c.subscribe(dragged.id);
        await new Promise((resolve) => setTimeout(resolve, 30));
      }
      await Promise.all(updates);
      const last = dragged.state.version;
      await Promise.all([dragged, watcher, late].map((s) => convergedAt(s, last)));
      assert.ok(moved > 0, 'moved vertices were applied');
      const mesh = positionTriangles(dragged.mesh);
      assert.deepEqual(positionTriangles(watcher.mesh), mesh, 'a version-2 subscriber');
      assert.deepEqual(positionTriangles(late.mesh), mesh, 'a version-1 subscriber from mid-drag');
      const fresh = await d.create({ ...definition, parameters: { a: 4.6 } });
      await converged(fresh);
      assert.deepEqual(positionTriangles(fresh.mesh), mesh, 'a fresh session of the last version');
      assert.equal(dragged.stats.resyncs + watcher.stats.resyncs + late.stats.resyncs, 0);
    } finally {
      for (const connection of [a, b, c, d]) connection.close();
    }
  });

  test('two subscribers, one of them joining late, end with identical meshes', async () => {
    const [a, b, c] = await Promise.all([client(server), client(server), client(server)]);
    try {
      const expression = 'x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0';
      const first = await a.create({ expression, box: BOX, constraints: { triangles: 60000 } });
      const second = await b.subscribe(first.id);
      await until(() => first.stats.deltas >= 3, { what: 'a few deltas' });
      const late = await c.subscribe(first.id);
      await Promise.all([converged(first), converged(second), converged(late)]);
      const reference = canonicalTriangles(first.mesh);
      assert.deepEqual(canonicalTriangles(second.mesh), reference);
      assert.deepEqual(canonicalTriangles(late.mesh), reference);
      assert.ok(late.stats.keyframes >= 1);
      assert.equal(first.mesh.sequence, late.mesh.sequence);
    } finally {
      for (const connection of [a, b, c]) connection.close();
    }
  });

  test('20 rapid updates (a slider) end at the last value', async () => {
    const connection = await client(server);
    try {
      const session = await connection.create({
        expression: 'x^2+y^2+z^2=a',
        parameters: { a: 1 },
        box: [-5, 5, -5, 5, -5, 5],
        constraints: { triangles: 6000 },
      });
      const updates = [];
      for (let a = 2; a <= 21; ++a) updates.push(session.update({ parameters: { a } }));
      await Promise.all(updates);
      assert.equal(session.state.version, 21);
      await converged(session);
      const mesh = session.mesh.toIndexed();
      assert.ok(watertight(mesh.indices));
      const step = (10 * (1 + 2 / 64)) / (2 ** 14 - 1);
      for (let v = 0; v < mesh.positions.length; v += 3) {
        const r = Math.hypot(mesh.positions[v], mesh.positions[v + 1], mesh.positions[v + 2]);
        assert.ok(Math.abs(r - Math.sqrt(21)) < 2 * step, `vertex at radius ${r}`);
      }
      assert.ok(mesh.indices.length / 3 <= 6000);
    } finally {
      connection.close();
    }
  });
});

describe('resources', () => {
  test('a client that stops reading for 5 s keeps server memory bounded, then converges', async () => {
    await withServer(['--queue-bytes', '65536'], async (server) => {
      // Version 1: its moves re-send whole meshes, the bytes this test needs to back the
      // server's writes up (version 2's moves are a few bytes a vertex).
      const [driver, reader] = await Promise.all([client(server, { protocolVersion: 1 }), client(server, { protocolVersion: 1 })]);
      try {
        // Two sessions whose every version moves every vertex, so that each re-sends its whole
        // mesh: more bytes in 5 s than the kernel's socket buffers hold (200,000 triangles each:
        // a version superseded while its vertices move sends no half-moved frame, and with
        // 100,000 too few bytes left on a busy machine). The driver only moves the sliders (it
        // unsubscribes, so decoding frames does not slow its updates down), and the
        // reader stops reading right after subscribing, before its receive buffer has grown (on
        // loopback Linux grows it up to tcp_rmem's maximum, 32 MB here, for a reader that keeps up).
        const sessions = await Promise.all([4, 5].map((a) =>
          driver.create({ expression: 'x^2+y^2+z^2=a', parameters: { a }, box: BOX, constraints: { triangles: 200000 } })));
        await Promise.all(sessions.map((s) => converged(s)));
        await Promise.all(sessions.map((s) => s.unsubscribe()));
        const before = server.status().rssKb;
        const watched = [];
        for (const s of sessions) watched.push(await reader.subscribe(s.id));
        reader.socket._socket.pause(); // stops reading: the server's writes back up

        let mostQueued = 0;
        let mostRss = before;
        const end = Date.now() + 5000;
        for (let i = 1; Date.now() < end; ++i) {
          await Promise.all(sessions.map((s, k) => s.update({ parameters: { a: 4 + k + 0.2 * Math.sin(i) } })));
          await new Promise((resolve) => setTimeout(resolve, 250));
          const metrics = await server.metrics();
          mostQueued = Math.max(mostQueued, metrics.get('isomesh_queued_bytes'));
          mostRss = Math.max(mostRss, server.status().rssKb);
        }
        const metrics = await server.metrics();
        const sent = metrics.get('isomesh_bytes_sent_total');
        assert.ok(metrics.get('isomesh_deltas_dropped_total') > 0,
          `deltas were dropped for the slow reader (${sessions[0].state.version} versions, ${sent} bytes sent)`);
        // The reader's budget (64 KiB) plus one keyframe per session (~2 bytes a triangle): a few
        // MB at most, however long the reader sleeps.
        assert.ok(mostQueued < 8 * 1024 * 1024, `queued ${mostQueued} bytes`);
        assert.ok(mostRss - before < 200 * 1024, `RSS grew by ${mostRss - before} kB`);

        reader.socket._socket.resume();
        // The driver subscribes again (a keyframe of the latest version) to hold the reference mesh.
        const reference = [];
        for (const s of sessions) reference.push(await driver.subscribe(s.id));
        for (let k = 0; k < sessions.length; ++k) {
          const version = sessions[k].state.version;
          await convergedAt(reference[k], version);
          await convergedAt(watched[k], version);
          assert.deepEqual(canonicalTriangles(watched[k].mesh), canonicalTriangles(reference[k].mesh));
        }
      } finally {
        driver.close();
        reader.close();
      }
    });
  });

  test('a client that vanishes mid-stream leaves no session or thread behind', async () => {
    await withServer(['--orphan-timeout', '0.5'], async (server) => {
      await until(async () => (await server.metrics()).get('isomesh_connections') === 0);
      const threadsBefore = server.status().threads;
      const connection = await client(server, { reconnect: false }); // gone for good
      const session = await connection.create({
        expression: 'x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0',
        box: BOX,
        constraints: { triangles: 500000 },
      });
      await until(() => session.stats.deltas >= 2, { what: 'refinement under way' });
      connection.socket._socket.destroy(); // no close frame: the client is just gone
      await until(
        async () => {
          const m = await server.metrics();
          return m.get('isomesh_sessions') === 0 && m.get('isomesh_connections') === 0 &&
            m.get('isomesh_busy_workers') === 0 && m.get('isomesh_subscriptions') === 0;
        },
        { timeoutMs: 10000, what: 'the session to expire' },
      );
      assert.equal(server.status().threads, threadsBefore);
      assert.equal((await server.metrics()).get('isomesh_sessions_expired_total'), 1);
    });
  });
});

describe('bad input', () => {
  test('every bad request gets its error code and the connection stays usable', async () => {
    const limits = ['--max-message-bytes', '4096', '--max-sessions-per-connection', '2', '--max-triangles', '100000'];
    await withServer(limits, async (server) => {
      const raw = await rawSocket(server);
      const create = (id, fields) => raw.send({ v: 1, type: 'create', id, box: BOX, ...fields });
      create(1, { expression: 'x^2+y^2+z^2=4', constraints: { triangles: 500 } });
      assert.equal((await raw.reply(1)).type, 'created');

      const cases = [
        [2, 'unknown_type', () => raw.send({ v: 1, type: 'teleport', id: 2 })],
        [3, 'unknown_session', () => raw.send({ v: 1, type: 'subscribe', id: 3, session: '0'.repeat(32) })],
        [4, 'bad_expression', () => create(4, { expression: 'x^2+y^2+(z=4' })],
        [6, 'budget_too_large', () => create(6, { expression: 'x=0', constraints: { triangles: 200000 } })],
        [7, 'bad_field', () => create(7, { expression: 'x^2+y^2+z^2=a' })],
        [8, 'bad_field', () => raw.send({ v: 1, type: 'create', id: 8, expression: 'x=0', box: [1, 0, 0, 1, 0, 1] })],
        [9, 'unsupported_version', () => raw.send({ v: 99, type: 'ping', id: 9 })],
      ];
      for (const [id, code, send] of cases) {
        send();
        const reply = await raw.reply(id);
        assert.equal(reply.type, 'error', `request ${id}`);
        assert.equal(reply.code, code, `request ${id}: ${reply.message}`);
      }
      assert.equal((await raw.reply(4)).column, 11); // the '=' inside the bracket

      // Too large, or nested too deeply, to be parsed: the reply still echoes the id.
      raw.send({ v: 1, type: 'ping', id: 5, pad: 'x'.repeat(5000) });
      assert.equal((await raw.reply(5)).code, 'too_large');
      raw.send(`{"v":1,"type":"ping","id":13,"x":${'['.repeat(40)}${']'.repeat(40)}}`);
      assert.equal((await raw.reply(13)).code, 'bad_json');
      // Names the function does not use are typos, not silently dropped.
      create(14, { expression: 'x^2+y^2+z^2=4', parameters: { b: 1 } });
      const typo = await raw.reply(14);
      assert.equal(typo.code, 'bad_field');
      assert.match(typo.message, /'b'/);

      raw.send('{not json');
      raw.socket.send(Buffer.from([1, 2, 3]), { binary: true }); // clients send no binary messages
      await until(() => raw.messages.filter((m) => m.type === 'error' && m.code === 'bad_json' && m.id === undefined).length === 2);

      create(10, { expression: 'x^2+y^2+z^2=1', constraints: { triangles: 100 } });
      assert.equal((await raw.reply(10)).type, 'created');
      create(11, { expression: 'x^2+y^2+z^2=2', constraints: { triangles: 100 } });
      assert.equal((await raw.reply(11)).code, 'too_many_sessions');

      raw.send({ v: 1, type: 'ping', id: 12 });
      assert.equal((await raw.reply(12)).type, 'pong');
      raw.close();
    });
  });

  test('a function over the evaluation time limit ends its session only', async () => {
    await withServer(['--eval-timeout-ms', '30'], async (server) => {
      const raw = await rawSocket(server);
      let heavy = '0';
      for (let i = 1; i <= 400; ++i) heavy += `+sin(${i}x+y*z)`;
      raw.send({ v: 1, type: 'create', id: 1, expression: `${heavy}=1`, box: BOX });
      assert.equal((await raw.reply(1)).type, 'created');
      await until(() => raw.messages.some((m) => m.type === 'error' && m.code === 'eval_timeout'));
      await until(() => raw.messages.some((m) => m.type === 'closed' && m.reason === 'error'));
      raw.send({ v: 1, type: 'create', id: 2, expression: 'x^2+y^2+z^2=4', box: BOX, constraints: { triangles: 500 } });
      assert.equal((await raw.reply(2)).type, 'created');
      await until(() => raw.messages.some((m) => m.type === 'converged'));
      raw.close();
    });
  });
});

describe('http', () => {
  test('/, /healthz, /metrics, and files from the web root only', async () => {
    const root = mkdtempSync(join(tmpdir(), 'isomesh-web-'));
    mkdirSync(join(root, 'site'));
    writeFileSync(join(root, 'site', 'index.html'), '<!doctype html><title>viewer</title>');
    writeFileSync(join(root, 'site', 'app.js'), 'export const answer = 42;');
    writeFileSync(join(root, 'secret.txt'), 'outside the web root');
    try {
      await withServer(['--web-root', join(root, 'site')], async (server) => {
        const get = (path) => fetch(`${server.httpUrl}${path}`);
        const index = await get('/');
        assert.equal(index.status, 200);
        assert.match(index.headers.get('content-type'), /text\/html/);
        assert.equal(await index.text(), '<!doctype html><title>viewer</title>');
        const script = await get('/app.js');
        assert.match(script.headers.get('content-type'), /text\/javascript/);
        assert.equal(await (await get('/healthz')).text(), 'ok\n');
        const metrics = await (await get('/metrics')).text();
        for (const name of ['isomesh_sessions', 'isomesh_connections', 'isomesh_splits_per_second',
          'isomesh_bytes_sent_total', 'isomesh_queued_bytes', 'isomesh_frame_latency_seconds_bucket']) {
          assert.match(metrics, new RegExp(`^${name}`, 'm'));
        }
        assert.equal((await get('/no/such/file.js')).status, 404);
        assert.equal((await get('/ws')).status, 426);
        assert.equal((await fetch(`${server.httpUrl}/`, { method: 'POST' })).status, 405);
        // Raw paths (fetch would normalize them away).
        for (const path of ['/../secret.txt', '/%2e%2e/secret.txt', '/..%2fsecret.txt', '/.hidden']) {
          assert.equal(await rawGetStatus(server.port, path), 403, path);
        }
      });
    } finally {
      rmSync(root, { recursive: true, force: true });
    }
  });

  test('without a web client, / is a built-in page', async () => {
    await withServer([], async (server) => {
      const index = await fetch(`${server.httpUrl}/`);
      assert.equal(index.status, 200);
      assert.match(await index.text(), /isomesh server/);
    });
  });

  test('SIGTERM drains: subscribers get closed, then a close frame, and the server exits 0', async () => {
    const server = await startServer();
    const raw = await rawSocket(server);
    raw.send({ v: 1, type: 'create', id: 1, expression: 'x^2+y^2+z^2=4', box: BOX, constraints: { triangles: 2000 } });
    assert.equal((await raw.reply(1)).type, 'created');
    await until(() => raw.frames.length >= 1, { what: 'the first keyframe' });
    const closeCode = new Promise((resolve) => raw.socket.once('close', (code) => resolve(code)));
    const { code } = await server.stop();
    assert.equal(code, 0);
    assert.equal(await closeCode, 1001); // going away
    assert.ok(raw.messages.some((m) => m.type === 'closed' && m.reason === 'shutdown'));
  });
});

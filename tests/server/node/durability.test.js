// Sessions that survive a crash: isomesh-server with its SQLite session store, killed with
// SIGKILL (no drain, nothing flushed) and started again on the same file and port. Every session
// comes back and converges to the identical mesh (the same triangles at bit-equal positions) and
// answers to its view id, read-only; closed and expired sessions do not come back.
//
//   cd tests/server/node && npm ci --no-audit --no-fund && node --test durability.test.js

import assert from 'node:assert/strict';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { client, converged, convergedAt, positionTriangles, startServer, until } from './harness.js';

const BOX = [-3, 3, -3, 3, -3, 3];
// The shared test data (a .vm model): $ISOMESH_SHARED_DIR, else ../shared beside the checkout.
const SHARED =
  process.env.ISOMESH_SHARED_DIR ?? fileURLToPath(new URL('../../../../shared/', import.meta.url));
const VM = join(SHARED, 'testdata/vm/tanglecube.vm');

/** Sessions of every kind a record must rebuild: expression, parameters, .vm, updates. */
const DEFINITIONS = [
  { expression: 'x^2+y^2+z^2+2cos(2x)=a', parameters: { a: 5 }, box: BOX, constraints: { triangles: 3000 } },
  { expression: '(sqrt(x^2+y^2)-1.8)^2+z^2=0.5', box: BOX, constraints: { triangles: 2500, error_measure: 'epsilon4' } },
  { vm: existsSync(VM) ? readFileSync(VM, 'utf8') : '', box: BOX, constraints: { triangles: 2000 } },
  { expression: '10x^2+y^2+z^2=b', parameters: { b: 5 }, box: BOX, constraints: { triangles: 1500, max_error: 0.001 } },
];

describe('SQLite session store', () => {
  let dir;
  before(() => {
    dir = mkdtempSync(join(tmpdir(), 'isomesh-durability-'));
  });
  after(() => rmSync(dir, { recursive: true, force: true }));

  test('after kill -9 every session resumes with the identical mesh; closed and expired ones do not come back', async (t) => {
    if (!existsSync(VM)) return t.skip(`no shared test data: ${VM} (set ISOMESH_SHARED_DIR)`);
    const store = ['--store', `sqlite:${join(dir, 'sessions.db')}`];
    let server = await startServer([...store, '--orphan-timeout', '1']);
    const port = String(server.port);
    const keeper = await client(server); // reconnects and resubscribes by itself
    let restarted = null;
    try {
      const sessions = [];
      for (const definition of DEFINITIONS) sessions.push(await keeper.create(definition));
      // A box update makes the session mesh its new box from scratch; a parameter update
      // refines from the mesh it had (so its mesh depends on when the update came).
      await sessions[1].update({ box: [-2.5, 2.5, -2.5, 2.5, -2.5, 2.5] });
      await sessions[3].update({ parameters: { b: 6 } });
      await Promise.all(sessions.map((s) => converged(s)));
      const before = sessions.map((s) => ({ id: s.id, view: s.view, state: s.state, mesh: positionTriangles(s.mesh) }));

      const closer = await keeper.create({ expression: 'x^2+y^2+z^2=4', box: BOX, constraints: { triangles: 500 } });
      await closer.close();
      const leaver = await client(server, { reconnect: false });
      const orphan = await leaver.create({ expression: 'x^2+y^2+z^2=2', box: BOX, constraints: { triangles: 500 } });
      leaver.close(); // no subscriber left: the session expires after the orphan timeout
      await until(async () => (await server.metrics()).get('isomesh_sessions_expired_total') === 1, { what: 'the orphan to expire' });

      const written = await server.metrics();
      assert.ok(written.get('isomesh_store_write_seconds_count') >= DEFINITIONS.length + 2, 'store writes are measured');
      assert.equal(written.get('isomesh_store_up'), 1);
      const reconnected = keeper.once('reconnected');
      await server.kill();
      restarted = await startServer([...store, '--port', port]);
      server = restarted;
      await reconnected;
      assert.equal((await server.metrics()).get('isomesh_sessions_restored_total'), DEFINITIONS.length);

      // The same Session objects, resubscribed by the library, and a new client subscribing.
      const viewer = await client(server);
      try {
        for (let i = 0; i < sessions.length; ++i) {
          const { id, state, mesh } = before[i];
          const watched = await viewer.subscribe(id);
          assert.deepEqual(watched.state, state, `session ${i}: the definition and version survive`);
          await convergedAt(watched, state.version);
          await converged(sessions[i]);
          if (i !== 3) {
            assert.deepEqual(positionTriangles(watched.mesh), mesh, `session ${i}: identical mesh`);
            assert.deepEqual(positionTriangles(sessions[i].mesh), mesh, `session ${i} (resubscribed)`);
          }
        }
        // The view id survives too, and is still read-only.
        assert.ok(before[0].view && before[0].view !== before[0].id);
        const viewed = await viewer.subscribe(before[0].view);
        assert.equal(viewed.access, 'view');
        assert.equal(viewed.view, undefined, 'a holder of the view id never learns the control id');
        await convergedAt(viewed, before[0].state.version);
        assert.deepEqual(positionTriangles(viewed.mesh), before[0].mesh, 'identical mesh by the view id');
        await assert.rejects(viewed.pause(), (e) => e.code === 'read_only');
        // The parameter-updated session converges to the mesh of its definition made afresh.
        const fresh = await viewer.create({ ...DEFINITIONS[3], parameters: { b: 6 } });
        await converged(fresh);
        assert.deepEqual(positionTriangles(sessions[3].mesh), positionTriangles(fresh.mesh));
        await fresh.close();

        for (const gone of [closer.id, orphan.id]) {
          await assert.rejects(viewer.subscribe(gone), (e) => e.code === 'unknown_session', `${gone} stays gone`);
        }
      } finally {
        viewer.close();
      }
    } finally {
      keeper.close();
      if (restarted) assert.equal((await restarted.stop()).code, 0);
      else await server.kill();
    }
  });
});

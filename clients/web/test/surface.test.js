import assert from 'node:assert/strict';
import { test } from 'node:test';

import { Emitter } from '../../js/src/events.js';
import { NEXT_UPDATE_WAIT_MS, RETRY_MS, Surface, mergeFields } from '../src/surface.js';

/** A session whose replies the test gives by hand. */
class FakeSession extends Emitter {
  constructor(fields) {
    super();
    this.id = 'f'.repeat(32);
    this.state = { version: 1, expression: fields.expression, parameters: fields.parameters, box: fields.box, constraints: {} };
    this.mesh = { functionVersion: 0, triangleCount: 0, synchronized: true, sequence: 0, slots: { count: 0 } };
    this.stats = { firstMeshMs: null };
    this.converged = false;
    this.lastProgress = null;
    this.lastConverged = null;
    this.closed = false;
    this.requests = []; // {fields, resolve, reject}
    this.pauses = 0;
  }

  update(fields) {
    return new Promise((resolve, reject) => this.requests.push({ fields, resolve, reject }));
  }

  /** Answers the oldest update (a new version), as the server's `updated`. */
  answer() {
    const { fields, resolve } = this.requests.shift();
    this.state = { ...this.state, version: this.state.version + 1, parameters: { ...this.state.parameters, ...fields.parameters } };
    this.emit('state', this.state);
    resolve(this.state);
  }

  /** A frame of the current version arrives. */
  frame() {
    this.mesh.functionVersion = this.state.version;
    this.emit('delta', { header: { kind: 'delta', sequence: 1, functionVersion: this.state.version, converged: false }, removed: [], triangleIds: [] });
  }

  /** The server's `converged` for the current version; the mesh on hand is final. */
  converge(fields = {}) {
    this.frame();
    this.lastConverged = { version: this.state.version, triangles: this.mesh.triangleCount, outcome: 'surface', certified: true, unresolved_cells: 0, budget_unreachable: false, ...fields };
    this.converged = true;
    this.emit('converged', this.lastConverged);
  }

  pause() {
    ++this.pauses;
    return Promise.resolve();
  }

  close() {
    this.closed = true;
    return Promise.resolve();
  }
}

/** A connected client: its `create` makes FakeSessions; `failures` reject the first creates in turn. */
function fakeClient({ failures = [] } = {}) {
  const client = Object.assign(new Emitter(), { closed: false, connected: true, sessions: [], creates: [] });
  client.create = async (fields) => {
    client.creates.push(fields);
    if (client.creates.length <= failures.length) throw failures[client.creates.length - 1];
    const session = new FakeSession(fields);
    client.sessions.push(session);
    return session;
  };
  return client;
}

const coded = (code, message = code) => Object.assign(new Error(message), { code });

const tick = () => new Promise((resolve) => setImmediate(resolve));
const shared = (parameters = { a: 1 }) => () => ({ parameters, box: [-1, 1, -1, 1, -1, 1], constraints: {} });

/** A surface of `expression` attached to a fake client, once its session is made. */
async function attached(expression, options = {}) {
  const client = fakeClient();
  const surface = new Surface({ expression, shared: shared(), ...options });
  surface.attach(client);
  await tick();
  return { client, surface, session: client.sessions[0] };
}

test('Surface: edits made while an update is in flight are merged into one, the latest value winning', async () => {
  const { client, surface, session } = await attached('x^2+y^2+z^2=a');
  assert.deepEqual(client.creates[0].parameters, { a: 1 });
  surface.setParameters({ a: 1.1 });
  for (const a of [1.2, 1.3, 1.4]) surface.setParameters({ a });
  surface.setParameters({ unused: 3 }); // a parameter this surface does not use: nothing sent
  assert.equal(session.requests.length, 1, 'one update in flight');
  session.answer();
  await tick();
  assert.equal(session.requests.length, 0, 'the next waits for the mesh of the answered version');
  session.frame();
  await tick();
  assert.equal(session.requests.length, 1);
  assert.deepEqual(session.requests[0].fields, { parameters: { a: 1.4 } }, 'merged: the latest value');
  assert.equal(surface.versionsShown, 1);
  session.answer();
  session.frame();
  await tick();
  assert.equal(surface.versionsShown, 2, 'each version whose mesh appeared counts once');
});

test('Surface: the next update goes after a short wait when the mesh is slow to come', async () => {
  const { surface, session } = await attached('x=a');
  surface.setParameters({ a: 2 });
  surface.setParameters({ a: 3 });
  session.answer();
  await tick();
  assert.equal(session.requests.length, 0);
  await new Promise((resolve) => setTimeout(resolve, NEXT_UPDATE_WAIT_MS + 50));
  assert.equal(session.requests.length, 1, 'sent without the mesh');
});

test('Surface: a rejected equation keeps the session and reports the error with its column', async () => {
  const client = fakeClient();
  const changes = [];
  const surface = new Surface({ expression: 'x=1', shared: shared(), onChange: (s, what) => changes.push(what) });
  surface.attach(client);
  await tick();
  const session = client.sessions[0];
  surface.setExpression('x=(1');
  const error = Object.assign(new Error('expected )'), { code: 'bad_expression', column: 5 });
  session.requests.shift().reject(error);
  await tick();
  assert.deepEqual(surface.error, { code: 'bad_expression', message: 'expected )', column: 5, text: 'x=(1' });
  assert.equal(surface.session, session, 'the previous surface stays');
  assert.ok(changes.includes('error'));
  session.emit('progress', { version: 1, error_max: 0.5 });
  assert.equal(surface.errorMax, 0.5);
  surface.setExpression('x=2');
  session.answer();
  await tick();
  assert.equal(surface.error, null, 'a good equation clears it');
  assert.equal(surface.errorMax, null, "a new version never shows the previous version's error");
  session.emit('progress', { version: 1, error_max: 0.7 });
  assert.equal(surface.errorMax, null, 'a late message of the previous version is ignored');
});

test('Surface: create retries once with the parameters the server says are missing', async () => {
  const missing = Object.assign(new Error("parameters: no value for parameter 'β'"), { code: 'bad_field' });
  const client = fakeClient({ failures: [missing] });
  const surface = new Surface({ expression: 'x=a', shared: shared({ a: 2 }) });
  surface.attach(client);
  await tick();
  await tick();
  assert.equal(client.creates.length, 2);
  assert.deepEqual(client.creates[1].parameters, { a: 2, β: 1 });
  assert.ok(surface.session);
});

test('Surface: a slider moved while the session is being created is sent once it exists', async () => {
  const client = fakeClient();
  const values = { a: 1 };
  const surface = new Surface({ expression: 'x=a', shared: () => ({ parameters: values, box: [-1, 1, -1, 1, -1, 1], constraints: {} }) });
  surface.attach(client); // create sent with a = 1
  values.a = 2;
  surface.setParameters({ a: 2 });
  await tick();
  const session = client.sessions[0];
  assert.deepEqual(client.creates[0].parameters, { a: 1 });
  assert.deepEqual(
    session.requests.map((r) => r.fields),
    [{ parameters: { a: 2 } }],
    'one update with the value the slider has now',
  );
});

test("Surface: status follows the session: the shape being found, refined, then the server's outcome", async () => {
  const client = fakeClient();
  const surface = new Surface({ shared: shared() });
  assert.equal(surface.status, 'empty');
  surface.attach(client);
  surface.setExpression('1/x=0');
  await tick();
  const session = client.sessions[0];
  assert.equal(surface.status, 'meshing');
  session.frame();
  session.lastProgress = { version: 1, resolving: true };
  assert.equal(surface.status, 'resolving');
  assert.equal(surface.snapshot().resolving, true);
  session.lastProgress = { version: 1, resolving: false };
  assert.equal(surface.status, 'refining');
  assert.equal(surface.finished, null, 'no outcome before convergence');
  session.converge({ outcome: 'no_surface' });
  assert.equal(surface.status, 'converged');
  assert.deepEqual(surface.snapshot().outcome, { outcome: 'no_surface', certified: true, unresolvedCells: 0, budgetUnreachable: false, triangles: 0 });
  surface.setExpression('1/x=a');
  assert.equal(surface.finished, null, 'an edit on its way: the outcome of the previous version is not shown');
});

test('Surface: a dropped connection keeps the session; edits wait and go after the reconnection', async () => {
  const { client, surface, session } = await attached('x=a');
  session.converge();
  client.connected = false;
  session.emit('disconnected');
  assert.equal(surface.status, 'disconnected');
  assert.equal(surface.session, session, 'the same session, its mesh still shown');
  surface.setParameters({ a: 3 }); // the library holds it until the new connection
  assert.deepEqual(session.requests.map((r) => r.fields), [{ parameters: { a: 3 } }]);
  client.connected = true;
  client.emit('reconnected', { attempts: 1, sessions: 1 });
  session.emit('resubscribed', session.state);
  await tick();
  assert.equal(client.creates.length, 1, 'no new session');
  assert.equal(surface.session, session);
});

test('Surface: a paused surface pauses its session again after resubscribing (the server does not keep it)', async () => {
  const { surface, session } = await attached('x=1');
  await surface.setPaused(true);
  assert.equal(session.pauses, 1);
  session.emit('resubscribed', session.state);
  assert.equal(session.pauses, 2);
});

test('Surface: a session the server lost is made again with the current values; other endings are not', async () => {
  const values = { a: 1 };
  const client = fakeClient();
  const surface = new Surface({ expression: 'x=a', shared: () => ({ parameters: values, box: [-1, 1, -1, 1, -1, 1], constraints: {} }) });
  surface.attach(client);
  await tick();
  values.a = 5;
  client.sessions[0].emit('closed', { type: 'closed', reason: 'lost' });
  await tick();
  assert.equal(client.creates.length, 2, 'closed (lost): a new session');
  assert.deepEqual(client.creates[1].parameters, { a: 5 });
  assert.equal(surface.session, client.sessions[1]);

  values.a = 6;
  surface.setParameters({ a: 6 });
  client.sessions[1].requests.shift().reject(coded('unknown_session'));
  await tick();
  assert.equal(client.creates.length, 3, 'unknown_session: a new session');
  assert.deepEqual(client.creates[2].parameters, { a: 6 }, 'with the value the failed update carried');
  assert.equal(surface.error, null, 'no error shown');

  client.sessions[2].emit('closed', { type: 'closed', reason: 'expired' });
  await tick();
  assert.equal(client.creates.length, 3, 'expired: no new session until the next edit');
  assert.equal(surface.session, null);
  assert.equal(surface.status, 'ended', 'and the surface says so');
  assert.equal(surface.snapshot().ended, 'expired');
  surface.setExpression('x=a+1');
  assert.equal(surface.status, 'meshing');
  await tick();
  assert.equal(client.creates.length, 4);
  assert.equal(surface.ended, null);

  client.sessions[3].emit('error', coded('eval_timeout', 'too slow'));
  client.sessions[3].emit('closed', { type: 'closed', reason: 'error' });
  assert.equal(surface.status, 'error', 'closed after an error: the error says why');
});

test('Surface: a create the server cannot take now is made again later, and the server says why meanwhile', async (t) => {
  t.mock.timers.enable({ apis: ['setTimeout'] });
  const client = fakeClient({ failures: [coded('store_unavailable', 'the session store is down'), coded('closed')] });
  const surface = new Surface({ expression: 'x=1', shared: shared() });
  surface.attach(client);
  await tick();
  assert.equal(surface.error?.message, 'the session store is down');
  assert.equal(surface.status, 'meshing', 'not an error of the equation: it will be drawn');
  t.mock.timers.tick(RETRY_MS);
  await tick();
  assert.equal(client.creates.length, 2, 'tried again after RETRY_MS');
  client.emit('reconnected', { attempts: 1, sessions: 0 }); // the second failed on a lost connection
  await tick();
  assert.equal(client.creates.length, 3, 'tried again after the reconnection');
  assert.ok(surface.session);
  assert.equal(surface.error, null);
});

test('mergeFields: later fields win, parameters and constraints merge by name', () => {
  assert.deepEqual(mergeFields(null, { box: [1] }), { box: [1] });
  assert.deepEqual(
    mergeFields({ parameters: { a: 1, b: 2 }, constraints: { triangles: 5 } }, { parameters: { a: 3 }, constraints: { max_error: 1 }, expression: 'x' }),
    { parameters: { a: 3, b: 2 }, constraints: { triangles: 5, max_error: 1 }, expression: 'x' },
  );
});

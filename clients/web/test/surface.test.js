import assert from 'node:assert/strict';
import { test } from 'node:test';

import { Emitter } from '../../js/src/events.js';
import { NEXT_UPDATE_WAIT_MS, Surface, mergeFields } from '../src/surface.js';

/** A session whose replies the test gives by hand. */
class FakeSession extends Emitter {
  constructor(fields) {
    super();
    this.id = 'f'.repeat(32);
    this.state = { version: 1, expression: fields.expression, parameters: fields.parameters, box: fields.box, constraints: {} };
    this.mesh = { functionVersion: 0, triangleCount: 0, synchronized: true, sequence: 0, slots: { count: 0 } };
    this.stats = { firstMeshMs: null };
    this.converged = false;
    this.closed = false;
    this.requests = []; // {fields, resolve, reject}
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

  close() {
    this.closed = true;
    return Promise.resolve();
  }
}

function fakeClient({ failFirst = null } = {}) {
  const client = { closed: false, sessions: [], creates: [] };
  client.create = async (fields) => {
    client.creates.push(fields);
    if (failFirst && client.creates.length === 1) throw failFirst;
    const session = new FakeSession(fields);
    client.sessions.push(session);
    return session;
  };
  return client;
}

const tick = () => new Promise((resolve) => setTimeout(resolve, 0));
const shared = (parameters = { a: 1 }) => () => ({ parameters, box: [-1, 1, -1, 1, -1, 1], constraints: {} });

test('Surface: edits made while an update is in flight are merged into one, the latest value winning', async () => {
  const client = fakeClient();
  const surface = new Surface({ expression: 'x^2+y^2+z^2=a', shared: shared() });
  surface.attach(client);
  await tick();
  const session = client.sessions[0];
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
  const client = fakeClient();
  const surface = new Surface({ expression: 'x=a', shared: shared() });
  surface.attach(client);
  await tick();
  const session = client.sessions[0];
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
  const client = fakeClient({ failFirst: missing });
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

test('Surface: status follows the session, and a converged empty version is reported empty', async () => {
  const client = fakeClient();
  const surface = new Surface({ shared: shared() });
  assert.equal(surface.status, 'empty');
  surface.attach(client);
  surface.setExpression('1/x=0');
  await tick();
  const session = client.sessions[0];
  assert.equal(surface.status, 'meshing');
  session.frame();
  session.converged = true;
  assert.equal(surface.status, 'converged');
  assert.equal(surface.empty, true);
});

test('mergeFields: later fields win, parameters and constraints merge by name', () => {
  assert.deepEqual(mergeFields(null, { box: [1] }), { box: [1] });
  assert.deepEqual(
    mergeFields({ parameters: { a: 1, b: 2 }, constraints: { triangles: 5 } }, { parameters: { a: 3 }, constraints: { max_error: 1 }, expression: 'x' }),
    { parameters: { a: 3, b: 2 }, constraints: { triangles: 5, max_error: 1 }, expression: 'x' },
  );
});

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { Emitter } from '../../js/src/events.js';
import { Connection } from '../src/connection.js';

const tick = () => new Promise((resolve) => setImmediate(resolve));

/** A connect() that fails `failures` times, then gives an Emitter standing for the client. */
function fakeConnect(failures) {
  const calls = [];
  const connect = async (url, options) => {
    calls.push({ url, options });
    if (calls.length <= failures) throw new Error('WebSocket connection failed');
    return Object.assign(new Emitter(), { closes: 0, close() { ++this.closes; } });
  };
  return { connect, calls };
}

test('Connection: the first connection is tried again with the given delays; then the library reconnects and the state says so', async (t) => {
  t.mock.timers.enable({ apis: ['setTimeout'] });
  const { connect, calls } = fakeConnect(2);
  const states = [];
  const connection = new Connection({ connect, url: 'ws://h/ws', options: { deferFrames: true }, delaysMs: [100, 400], onChange: (c) => states.push(`${c.state}:${c.detail.split(':')[0]}`) });
  assert.equal(connection.state, 'connecting');
  const opened = connection.open();
  await tick();
  assert.equal(calls.length, 1);
  assert.equal(connection.state, 'disconnected');
  t.mock.timers.tick(99);
  await tick();
  assert.equal(calls.length, 1, 'waits the first delay');
  t.mock.timers.tick(1);
  await tick();
  assert.equal(calls.length, 2);
  t.mock.timers.tick(400);
  const client = await opened;
  assert.equal(calls.length, 3, 'the last delay repeats');
  assert.deepEqual(calls[2], { url: 'ws://h/ws', options: { deferFrames: true } });
  assert.equal(connection.client, client);
  assert.equal(connection.state, 'open');

  client.emit('disconnected', { code: 1006, reason: '' });
  assert.deepEqual([connection.state, connection.detail], ['disconnected', 'reconnecting']);
  client.emit('reconnected', { attempts: 2, sessions: 1 });
  assert.deepEqual([connection.state, connection.detail], ['open', '']);
  assert.deepEqual(states, [
    'disconnected:server unreachable, retrying',
    'disconnected:server unreachable, retrying',
    'open:',
    'disconnected:reconnecting',
    'open:',
  ]);
});

test('Connection: stop() ends the attempts and closes an open client', async (t) => {
  t.mock.timers.enable({ apis: ['setTimeout'] });
  const failing = fakeConnect(Infinity);
  const connection = new Connection({ connect: failing.connect, url: 'ws://h/ws', options: {}, delaysMs: [1000] });
  const opened = connection.open();
  await tick();
  connection.stop();
  assert.equal(await opened, null);
  assert.equal(failing.calls.length, 1, 'no attempt after stop');

  const { connect } = fakeConnect(0);
  const other = new Connection({ connect, url: 'ws://h/ws', options: {}, delaysMs: [1000] });
  const client = await other.open();
  other.stop();
  assert.equal(client.closes, 1);
});

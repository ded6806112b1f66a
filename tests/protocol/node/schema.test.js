// Validates the control messages the C++ library writes against protocol/schema/*.json (draft
// 2020-12, with Ajv), and checks the schemas reject what the C++ parser rejects.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import Ajv2020 from 'ajv/dist/2020.js';

const here = path.dirname(fileURLToPath(import.meta.url));
const schemaDir = path.resolve(here, '../../../protocol/schema');
const tool =
  process.env.ISOMESH_PROTOCOL_SAMPLE ?? path.resolve(here, '../../../build/bin/isomesh-protocol-sample');
const base = 'https://isomesh.example/schema/v1/';

let ajv;
let samples;
const validator = (name) => ajv.getSchema(base + name);

before(() => {
  ajv = new Ajv2020({ strict: true, strictRequired: false, allErrors: true });
  for (const file of fs.readdirSync(schemaDir)) {
    ajv.addSchema(JSON.parse(fs.readFileSync(path.join(schemaDir, file), 'utf8')));
  }
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'isomesh-messages-'));
  execFileSync(tool, ['messages', dir]);
  samples = Object.fromEntries(
    fs.readdirSync(dir).map((file) => [
      path.basename(file, '.json'),
      JSON.parse(fs.readFileSync(path.join(dir, file), 'utf8')),
    ]),
  );
});

const requests = ['create', 'update', 'subscribe', 'unsubscribe', 'pause', 'resume', 'close', 'resync', 'ping'];
const replies = ['created', 'updated', 'subscribed', 'ack', 'pong', 'progress', 'converged', 'error', 'closed'];

test('there is a schema and a C++ sample for every message type', () => {
  for (const type of [...requests, ...replies]) {
    assert.ok(validator(`${type}.json`), `schema ${type}`);
    assert.ok(samples[type], `sample ${type}`);
  }
});

test('every C++ sample validates against its schema and the union schema', () => {
  for (const type of [...requests, ...replies]) {
    const validate = validator(`${type}.json`);
    assert.ok(validate(samples[type]), `${type}: ${ajv.errorsText(validate.errors)}`);
    const union = validator(requests.includes(type) ? 'client-message.json' : 'server-message.json');
    assert.ok(union(samples[type]), `${type} in the union: ${ajv.errorsText(union.errors)}`);
  }
});

test('schemas reject malformed messages', () => {
  const session = samples.subscribe.session;
  const invalid = [
    ['ping.json', { v: 3, type: 'ping' }],
    ['ping.json', { v: 1, type: 'ping', extra: 1 }],
    ['ping.json', { v: 1, type: 'ping', id: 1.5 }],
    ['create.json', { v: 1, type: 'create', expression: 'x' }],
    ['create.json', { v: 1, type: 'create', box: [0, 1, 0, 1, 0, 1] }],
    ['create.json', { v: 1, type: 'create', expression: 'x', vm: 'y', box: [0, 1, 0, 1, 0, 1] }],
    ['create.json', { v: 1, type: 'create', expression: 'x', box: [0, 1], constraints: {} }],
    ['create.json', { v: 1, type: 'create', expression: 'x', box: [0, 1, 0, 1, 0, 1], constraints: { triangles: 0 } }],
    ['update.json', { v: 1, type: 'update', session }],
    ['subscribe.json', { v: 1, type: 'subscribe', session: 'xyz' }],
    ['subscribe.json', { v: 1, type: 'subscribe', session, more: true }],
    ['error.json', { v: 1, type: 'error', code: 'Not A Code', message: 'm' }],
    ['error.json', { v: 1, type: 'error', code: 'internal' }],
    ['created.json', { ...samples.created, access: 'admin' }],
    ['ping.json', { v: 1, type: 'ping', id: '😀'.repeat(65) }],
    ['client-message.json', { v: 1, type: 'created', session }],
  ];
  for (const [schema, message] of invalid) {
    assert.equal(validator(schema)(message), false, `${schema} accepted ${JSON.stringify(message)}`);
  }
});

test('server-message schemas allow what PROTOCOL.md 9 allows: new fields, codes and reasons', () => {
  const extended = [
    ['created.json', { ...samples.created, new_field: { any: 1 } }],
    ['pong.json', { ...samples.pong, new_field: 1 }],
    ['progress.json', { ...samples.progress, certified: true }],
    ['converged.json', { ...samples.converged, certified: true }],
    ['error.json', { v: 1, type: 'error', code: 'from_the_future', message: 'm', hint: 'h' }],
    ['closed.json', { v: 1, type: 'closed', session: samples.closed.session, reason: 'migrated' }],
    ['ack.json', { ...samples.ack, extra: [1] }],
  ];
  for (const [schema, message] of extended) {
    const validate = validator(schema);
    assert.ok(validate(message), `${schema}: ${ajv.errorsText(validate.errors)}`);
    assert.ok(validator('server-message.json')(message), `${schema} in the union`);
  }
});

test('string limits count characters (code points), as maxLength does and as the server does', () => {
  // 64 four-byte characters: 256 bytes of UTF-8, 128 UTF-16 units, 64 characters.
  const id = '😀'.repeat(64);
  assert.ok(validator('ping.json')({ v: 1, type: 'ping', id }));
  const echoed = JSON.parse(execFileSync(tool, ['echo-id', JSON.stringify(id)], { encoding: 'utf8' }));
  assert.deepEqual(echoed, { accepted: true });
  const tooLong = JSON.parse(execFileSync(tool, ['echo-id', JSON.stringify(id + 'x')], { encoding: 'utf8' }));
  assert.deepEqual(tooLong, { accepted: false });
});

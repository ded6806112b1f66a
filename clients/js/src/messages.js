// Control messages: the JSON text frames of the isomesh protocol (PROTOCOL.md, "Control
// messages"). Every message carries "v" (the protocol version) and "type"; requests may carry a
// client-chosen "id" that the reply echoes.

import { ERROR_CODES, IsomeshError } from './errors.js';

/**
 * The protocol version this library asks for by default: "v" of every message, byte 4 of every
 * frame. Version 2 differs from 1 only in its binary frames (PROTOCOL.md 4.5); a connection
 * speaks the version of its first message (options.protocolVersion of connect()).
 */
export const PROTOCOL_VERSION = 2;
/** The versions this library speaks. */
export const PROTOCOL_VERSIONS = Object.freeze([1, 2]);

/** Server-to-client messages that answer a request and echo its "id". */
export const REPLY_TYPES = new Set(['created', 'updated', 'subscribed', 'ack', 'pong', 'error']);

/**
 * The JSON text of a request. `fields` are the message's own fields; undefined ones are left out.
 * @param {string} type 'create', 'update', 'subscribe', ...
 */
export function requestText(type, id, fields = {}, version = PROTOCOL_VERSION) {
  const message = { v: version, type };
  if (id !== undefined) message.id = id;
  for (const [key, value] of Object.entries(fields)) {
    if (value !== undefined) message[key] = value;
  }
  return JSON.stringify(message);
}

/**
 * The fields of a `create` or `update` from the library's option object:
 * {expression | vm, parameters, box, constraints}. Checks shapes that JSON would silently mangle
 * (NaN, Infinity); the server validates everything else.
 */
export function functionFields({ expression, vm, parameters, box, constraints } = {}) {
  if (expression !== undefined && vm !== undefined) {
    throw new TypeError('give either expression or vm, not both');
  }
  if (expression !== undefined && typeof expression !== 'string') throw new TypeError('expression must be a string');
  if (vm !== undefined && typeof vm !== 'string') throw new TypeError('vm must be a string');
  if (parameters !== undefined) {
    for (const [name, value] of Object.entries(parameters)) {
      if (!Number.isFinite(value)) throw new TypeError(`parameter ${name} must be a finite number`);
    }
  }
  if (box !== undefined && !(Array.isArray(box) && box.length === 6 && box.every(Number.isFinite))) {
    throw new TypeError('box must be [x0, x1, y0, y1, z0, z1] of finite numbers');
  }
  if (constraints !== undefined) {
    const { triangles, max_error: maxError } = constraints;
    if (triangles !== undefined && !(Number.isSafeInteger(triangles) && triangles >= 1)) {
      throw new TypeError('constraints.triangles must be an integer >= 1');
    }
    if (maxError !== undefined && !(Number.isFinite(maxError) && maxError >= 0)) {
      throw new TypeError('constraints.max_error must be a finite number >= 0');
    }
  }
  return { expression, vm, parameters, box, constraints };
}

/**
 * Parses a server-to-client text frame. Throws IsomeshError('bad_json' | 'unsupported_version' |
 * 'bad_field') when it is not a message of this protocol version. Unknown fields are kept: servers
 * of the same version may add fields.
 */
export function parseServerMessage(text) {
  let message;
  try {
    message = JSON.parse(text);
  } catch (error) {
    throw new IsomeshError('bad_json', `server sent invalid JSON: ${error.message}`);
  }
  if (message === null || typeof message !== 'object' || Array.isArray(message)) {
    throw new IsomeshError('bad_json', 'server message is not a JSON object');
  }
  // A server writes its connection's version, and "v": 1 until the connection's first message
  // parsed (PROTOCOL.md 9).
  if (!PROTOCOL_VERSIONS.includes(message.v)) {
    throw new IsomeshError('unsupported_version', `server message of protocol version ${message.v}`);
  }
  if (typeof message.type !== 'string') throw new IsomeshError('bad_field', 'server message without a type');
  return message;
}

/** The session state of a created/updated/subscribed reply. */
export function sessionState(reply) {
  const { version, expression, vm, parameters, box, constraints } = reply;
  return { version, expression, vm, parameters: parameters ?? {}, box, constraints };
}

/** An IsomeshError from an `error` message; a code this version does not know reads as 'internal'. */
export function errorFromReply(reply) {
  const code = ERROR_CODES.includes(reply.code) ? reply.code : 'internal';
  return new IsomeshError(code, reply.message ?? '', {
    column: reply.column,
    session: reply.session,
    requestId: reply.id,
  });
}

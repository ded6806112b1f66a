// Errors of the isomesh protocol: a stable code (PROTOCOL.md, "Error codes") and a message.

/**
 * An error reply from the server (code, message, optional 1-based column of a bad expression) or
 * a local failure with the same codes, e.g. 'bad_frame' for a malformed binary frame.
 */
export class IsomeshError extends Error {
  /**
   * @param {string} code a protocol error code: 'bad_expression', 'unknown_session', ...
   * @param {string} message for a human
   * @param {{column?: number, session?: string, requestId?: number|string}} [details]
   */
  constructor(code, message, details = {}) {
    super(message);
    this.name = 'IsomeshError';
    this.code = code;
    if (details.column !== undefined) this.column = details.column;
    if (details.session !== undefined) this.session = details.session;
    if (details.requestId !== undefined) this.requestId = details.requestId;
  }
}

/** The error codes of protocol version 1, in their wire spelling. */
export const ERROR_CODES = Object.freeze([
  'bad_json',
  'unsupported_version',
  'unknown_type',
  'bad_field',
  'unknown_session',
  'bad_expression',
  'too_large',
  'too_many_sessions',
  'budget_too_large',
  'eval_timeout',
  'unavailable',
  'internal',
  'bad_frame',
  'store_unavailable',
  'wrong_route',
  'read_only',
  'server_busy',
  'resource_limit',
]);

// isomesh-client: a small client library for the isomesh protocol (see ../README.md).

export { connect, IsomeshClient, Session, routeOf, RECONNECT_DELAYS_MS } from './client.js';
export { loadDracoDecoder } from './draco_loader.js';
export { DracoMeshDecoder } from './draco.js';
export { IsomeshError, ERROR_CODES } from './errors.js';
export { Emitter } from './events.js';
export {
  decodeFrame,
  readFrameHeader,
  FRAME_HEADER_BYTES,
  FRAME_FLAG_CONVERGED,
  FRAME_FLAG_CATCH_UP,
} from './frame.js';
export { SessionMesh, VertexTable, Outcome } from './mesh.js';
export { PROTOCOL_VERSION, parseServerMessage, requestText } from './messages.js';
export { TriangleSlots } from './slots.js';
export {
  readVarint,
  appendVarint,
  decodeSortedIds,
  encodeSortedIds,
  decodeIdSequence,
  encodeIdSequence,
  MAX_TRIANGLE_ID,
} from './varint.js';

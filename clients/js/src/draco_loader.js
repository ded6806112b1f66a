// Loading Google's Draco decoder (npm `draco3d`, WebAssembly) once per page or process.
//
// draco3d's decoder script runs in Node (it reads draco_decoder.wasm beside itself) and in
// browsers, where the page says where the .wasm file is served: pass `locateFile` (or the bytes as
// `wasmBinary`), e.g. with Vite: `import wasmUrl from 'draco3d/draco_decoder.wasm?url'` and
// `loadDracoDecoder({ locateFile: () => wasmUrl })`.

import createDecoderModule from 'draco3d/draco_decoder_nodejs.js';

import { DracoMeshDecoder } from './draco.js';

/**
 * Resolves with a DracoMeshDecoder.
 * @param {{locateFile?: (name: string) => string, wasmBinary?: ArrayBuffer}} [moduleOptions]
 *   Emscripten module options for draco3d; none are needed in Node.
 */
export async function loadDracoDecoder(moduleOptions = {}) {
  const draco = await createDecoderModule({ ...moduleOptions });
  return new DracoMeshDecoder(draco);
}

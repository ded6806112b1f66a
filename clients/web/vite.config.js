// Vite configuration of the browser viewer.
//
// `npm run build` writes the static site to build/web at the repository root (next to build/bin),
// isomesh-server's default web root (served at GET /). Everything (three.js, the Draco decoder's
// .wasm) is bundled: the page needs no internet access.
//
// embed.html is the example page of the <isomesh-surface> element (src/isomesh_surface.js), also
// built on its own as build/web/isomesh-surface.js for other pages to load.
//
// `npm run dev` serves the viewer with hot reload on 127.0.0.1:5173 and forwards /ws to a server
// on 127.0.0.1:8080 (ISOMESH_SERVER overrides).
import { fileURLToPath } from 'node:url';

import { defineConfig } from 'vite';

const here = (path) => fileURLToPath(new URL(path, import.meta.url));

export default defineConfig({
  base: './',
  resolve: {
    // The client library is used from source (clients/js); its draco3d import resolves here.
    alias: {
      'isomesh-client': here('../js/src/index.js'),
      fs: here('src/node_stub.js'),
      path: here('src/node_stub.js'),
    },
    dedupe: ['draco3d'],
  },
  build: {
    outDir: here('../../build/web'),
    emptyOutDir: true,
    target: 'es2022',
    chunkSizeWarningLimit: 1024,
    rollupOptions: {
      // The viewer, the <isomesh-surface> example page, and the element's script under a fixed
      // name (build/web/isomesh-surface.js) that other pages load.
      input: {
        main: here('index.html'),
        embed: here('embed.html'),
        'isomesh-surface': here('src/isomesh_surface.js'),
      },
      output: {
        entryFileNames: (chunk) => (chunk.name === 'isomesh-surface' ? 'isomesh-surface.js' : 'assets/[name]-[hash].js'),
      },
    },
  },
  server: {
    host: '127.0.0.1',
    proxy: { '/ws': { target: process.env.ISOMESH_SERVER ?? 'ws://127.0.0.1:8080', ws: true } },
  },
});

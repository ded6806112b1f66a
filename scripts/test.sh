#!/usr/bin/env bash
# Installs what isomesh needs, builds everything, and runs every test: the unit and integration
# suites (ctest), the same suites with asserts and AddressSanitizer/UBSan (scripts/test-asan.sh),
# then the fuzz targets for a fixed time each, then the JavaScript client's unit tests and the
# browser test of the viewer (Debian's chromium, playwright-core; screenshots in
# build/test-artifacts/web). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DISOMESH_BUILD_TESTS=ON -DISOMESH_BUILD_BENCH=ON
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600
bash scripts/test-asan.sh
# The server end to end: real isomesh-servers on loopback ports, WebSocket clients applying every
# frame (tests/server/node: meshes equal to `isomesh mesh`, slow and vanished clients, bad input;
# sessions surviving kill -9 with SQLite; the deploy/ cluster with Redis and HAProxy). One file at
# a time: the cluster test's servers would slow the timing-sensitive ones of another file down.
(cd tests/server/node && npm ci --no-audit --no-fund && node --test --test-concurrency=1)
# The protocol's Node check: draco3d decodes frames and Ajv validates messages made by the C++ side.
(cd tests/protocol/node && npm ci --no-audit --no-fund && node --test)
# The CLI's .glb passes Khronos's gltf-validator and decodes with draco3d to the .ply's triangles.
(cd tests/export && npm ci --no-audit --no-fund && node --test)
bash scripts/fuzz.sh
# The client library (clients/js: varints, frames, slot table, sessions, frames of the C++
# encoder) and the viewer's pure modules (clients/web/test).
node --test clients/js/test/ clients/web/test/
# The viewer and its <isomesh-surface> element in Debian's chromium, served by a real isomesh-server on
# a free loopback port (tests/web: viewer, layout, embed, streaming, reconnect, expiry; screenshots in
# build/test-artifacts/web).
node --test tests/web/

#!/usr/bin/env bash
# The main job: installs what isomesh needs, builds it, and starts the mesh server with the browser
# client (build/web) on port 8080 (ISOMESH_PORT or --port to change), printing the URL to open.
# Extra arguments go to isomesh-server (see build/bin/isomesh-server --help). Ctrl-C stops it
# cleanly (sessions are closed, queued frames sent).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DISOMESH_BUILD_TESTS=OFF -DISOMESH_BUILD_BENCH=OFF
exec ./build/bin/isomesh-server --web-root build/web "$@"

#!/usr/bin/env bash
# Configures and builds isomesh (Release) into build/. Binaries land in build/bin/; the browser
# client (clients/web, built by Vite) lands in build/web, isomesh-server's default web root.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j "$jobs"

# npm packages, pinned by each folder's package-lock.json; `npm ci` only when node_modules is
# missing or older than the lock file. Vite 6 runs on Debian 12's Node 18 as on newer ones.
npm_ci() {
  if [ ! -f "$1/node_modules/.package-lock.json" ] || [ "$1/package-lock.json" -nt "$1/node_modules/.package-lock.json" ]; then
    (cd "$1" && npm ci --no-audit --no-fund)
  fi
}
for dir in clients/js clients/web tests/web; do npm_ci "$dir"; done
(cd clients/web && npm run build)

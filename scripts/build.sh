#!/usr/bin/env bash
# Configures and builds isomesh (Release) into build/. Binaries land in build/bin/; the browser
# client (clients/web, built by Vite) lands in build/web, isomesh-server's default web root.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j "$jobs"
echo "build: C++ built in $SECONDS s"

# npm packages, pinned by each folder's package-lock.json; installed only when node_modules is
# missing or older than the lock file. Vite 6 runs on Debian 12's Node 18 as on newer ones.
# clients/web uses `npm install --no-save` rather than `npm ci`: Vite's bundler (rollup) lists one
# optional native package per platform, and a registry mirror that serves only this platform's
# leaves the others out of the lock file, which `npm ci` then refuses. `--no-save` still installs
# exactly the locked versions and never rewrites the lock.
npm_install() {
  local dir=$1
  shift
  if [ ! -f "$dir/node_modules/.package-lock.json" ] || [ "$dir/package-lock.json" -nt "$dir/node_modules/.package-lock.json" ]; then
    (cd "$dir" && npm "$@" --no-audit --no-fund)
  fi
}
npm_install clients/js ci
npm_install clients/web install --no-save
npm_install tests/web ci
(cd clients/web && npm run build)

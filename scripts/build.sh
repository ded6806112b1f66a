#!/usr/bin/env bash
# Configures and builds isomesh (Release) into build/. Binaries land in build/bin/.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j "$jobs"

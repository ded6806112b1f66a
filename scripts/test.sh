#!/usr/bin/env bash
# Installs what isomesh needs, builds everything, and runs every test: the unit and integration
# suites (ctest), then the fuzz targets for a fixed time each. Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DISOMESH_BUILD_TESTS=ON -DISOMESH_BUILD_BENCH=ON
ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600
bash scripts/fuzz.sh

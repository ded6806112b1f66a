#!/usr/bin/env bash
# The main job: installs what isomesh needs, builds it, and meshes the default example.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DISOMESH_BUILD_TESTS=OFF -DISOMESH_BUILD_BENCH=OFF
expr=${1:-"x^2+y^2+z^2+2cos(2x)=5"}
./build/bin/isomesh mesh "$expr" --stats -o build/example.ply
echo "wrote build/example.ply for: $expr"

#!/usr/bin/env bash
# Builds the libFuzzer targets with clang into build-fuzz/ and runs each on its corpus under
# tests/fuzz/<target>/ for a fixed time (FUZZ_SECONDS, default 60 for the parser). New inputs
# go to a scratch folder, so the committed corpus only changes by hand. Asserts are compiled in
# (ISOMESH_ASSERTS), so a broken invariant is a finding too.
set -euo pipefail
cd "$(dirname "$0")/.."
: "${FUZZ_SECONDS_FRAME_DECODER:=20}"
: "${FUZZ_SECONDS_CONTROL_MESSAGE:=20}"
: "${FUZZ_SECONDS_CONTROL_HANDLING:=20}"
if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ not found, fuzz targets skipped"; exit 0
fi
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DISOMESH_FUZZ=ON -DISOMESH_ASSERTS=ON -DISOMESH_BUILD_BENCH=OFF >/dev/null
targets=$(cd tests/fuzz && ls -d */ 2>/dev/null | tr -d / || true)
for t in $targets; do
  built=$SECONDS
  cmake --build build-fuzz -j "$(nproc)" --target "fuzz_$t"
  echo "fuzz: fuzz_$t built in $((SECONDS - built)) s"
  seconds_var="FUZZ_SECONDS_${t^^}"
  seconds=${!seconds_var:-${FUZZ_SECONDS:-60}}
  scratch=$(mktemp -d)
  echo "fuzz: $t for ${seconds}s"
  log="build-fuzz/$t.log"
  status=0
  ./build-fuzz/bin/"fuzz_$t" -max_total_time="$seconds" -print_final_stats=1 \
    -artifact_prefix="build-fuzz/$t-" "$scratch" "tests/fuzz/$t" >"$log" 2>&1 || status=$?
  rm -rf "$scratch"
  if [ "$status" -ne 0 ]; then
    # The sanitizer's report (where, what, which threads), not just libFuzzer's final lines.
    echo "fuzz: $t failed (exit $status); its report, from $log:"
    sed -n '/ERROR:/,$p' "$log" | head -n 120
    tail -n 12 "$log"
    exit "$status"
  fi
  tail -n 12 "$log"
done

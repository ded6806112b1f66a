#!/usr/bin/env bash
# Builds the libFuzzer targets with clang into build-fuzz/ and runs each on its corpus under
# tests/fuzz/<target>/ for a fixed time (FUZZ_SECONDS, default 60 for the parser). New inputs
# go to a scratch folder, so the committed corpus only changes by hand. Asserts are compiled in
# (ISOMESH_ASSERTS), so a broken invariant is a finding too, and so is undefined behaviour
# (halt_on_error: UBSan would otherwise print its report and go on).
#
# The targets run side by side, as many at a time as there are cores (each is one process on one
# core, and its time is a fixed budget of its own), the longest first.
set -euo pipefail
cd "$(dirname "$0")/.."
: "${FUZZ_SECONDS_FRAME_DECODER:=20}"
: "${FUZZ_SECONDS_CONTROL_MESSAGE:=20}"
: "${FUZZ_SECONDS_CONTROL_HANDLING:=20}"
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ not found, fuzz targets skipped"; exit 0
fi
# -O1 -gline-tables-only: OSS-Fuzz's flags (line tables are all a sanitizer's stack trace reads);
# the build's CPU time 573 -> 364 s against RelWithDebInfo's -O2 -g (same run, 2 cores).
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DISOMESH_FUZZ=ON -DISOMESH_ASSERTS=ON -DISOMESH_BUILD_BENCH=OFF >/dev/null

seconds_of() {
  local var="FUZZ_SECONDS_${1^^}"
  echo "${!var:-${FUZZ_SECONDS:-60}}"
}
# Longest first, so that the shorter ones run beside it.
targets=$(for dir in tests/fuzz/*/; do
  t=$(basename "$dir")
  echo "$(seconds_of "$t") $t"
done | sort -rn | cut -d' ' -f2)
executables=()
for t in $targets; do executables+=("fuzz_$t"); done
cmake --build build-fuzz -j "$(nproc)" --target "${executables[@]}"
echo "fuzz: built in $SECONDS s"

# Runs target $1 into build-fuzz/$1.log; exits with its status.
run_target() {
  local t=$1 scratch status=0
  scratch=$(mktemp -d)
  ./build-fuzz/bin/"fuzz_$t" -max_total_time="$(seconds_of "$t")" -print_final_stats=1 \
    -artifact_prefix="build-fuzz/$t-" "$scratch" "tests/fuzz/$t" >"build-fuzz/$t.log" 2>&1 ||
    status=$?
  rm -rf "$scratch"
  return "$status"
}

declare -A pid_of
for t in $targets; do
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  echo "fuzz: $t for $(seconds_of "$t")s"
  run_target "$t" &
  pid_of[$t]=$!
done
failed=0
for t in $targets; do
  status=0
  wait "${pid_of[$t]}" || status=$?
  log="build-fuzz/$t.log"
  if [ "$status" -ne 0 ]; then
    # The sanitizer's report (where, what, which threads), not just libFuzzer's final lines.
    echo "fuzz: $t failed (exit $status); its report, from $log:"
    sed -n '/ERROR:/,$p' "$log" | head -n 120
    failed=$status
  else
    echo "fuzz: $t passed; from $log:"
  fi
  tail -n 12 "$log"
done
exit "$failed"

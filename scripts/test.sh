#!/usr/bin/env bash
# Installs what isomesh needs, builds everything, and runs every test: the unit and integration
# suites (ctest), the same suites with asserts and AddressSanitizer/UBSan (scripts/test-asan.sh),
# then the fuzz targets for a fixed time each, then the JavaScript client's unit tests and the
# browser test of the viewer (Debian's chromium, playwright-core; screenshots in
# build/test-artifacts/web). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each part's wall time and CPU time (user + system, of the processes it waited for), with the
# load average (the machine may be shared: wall time then grows, CPU time hardly), and a table of
# them at the end: the whole command must stay under 30 minutes on 2 cores.
summary=()
times_file=$(mktemp)
trap 'rm -f "$times_file"' EXIT
# cpu_now: the CPU seconds of the processes this shell waited for so far (`times` run in this
# shell itself: in a subshell, $(...), it would count that subshell's children only).
children_cpu() {
  times >"$times_file"
  cpu_now=$(awk 'NR == 2 { split($1 " " $2, t, /[ ms]+/); print t[1] * 60 + t[2] + t[3] * 60 + t[4] }' "$times_file")
}
part() {
  local name=$1 start=$SECONDS cpu line
  children_cpu
  cpu=$cpu_now
  shift
  "$@"
  children_cpu
  line=$(printf '%5d s  %5.0f s CPU  %-14s load %s' $((SECONDS - start)) \
    "$(awk "BEGIN { print $cpu_now - $cpu }")" "$name" "$(cut -d' ' -f1-3 /proc/loadavg)")
  summary+=("$line")
  echo "test.sh: $line"
}
ctest_release() { ctest --test-dir build --output-on-failure -j "$(nproc)" --timeout 600; }
node_suite() { (cd "$1" && npm ci --no-audit --no-fund && shift && node --test "$@"); }
part install-deps bash scripts/install-deps.sh
part build bash scripts/build.sh -DISOMESH_BUILD_TESTS=ON -DISOMESH_BUILD_BENCH=ON
# The release suites wait on servers, sockets and child processes more than they compute (about
# 100 s of CPU in 230 s): they run beside the sanitized build, which only computes. Their output
# follows the sanitized part's.
ctest_beside_asan() {
  local log status=0 pid
  log=$(mktemp)
  ctest_release >"$log" 2>&1 &
  pid=$!
  bash scripts/test-asan.sh || status=$?
  wait "$pid" || status=$?
  echo "test.sh: the release build's ctest (run beside the sanitized build):"
  cat "$log"
  rm -f "$log"
  return "$status"
}
part ctest+asan ctest_beside_asan
# The server end to end: real isomesh-servers on loopback ports, WebSocket clients applying every
# frame (tests/server/node: meshes equal to `isomesh mesh`, slow and vanished clients, bad input;
# sessions surviving kill -9 with SQLite; the deploy/ cluster with Redis and HAProxy). One file at
# a time: the cluster test's servers would slow the timing-sensitive ones of another file down.
part node-server node_suite tests/server/node --test-concurrency=1
# The protocol's Node check: draco3d decodes frames and Ajv validates messages made by the C++ side.
part node-protocol node_suite tests/protocol/node
# The CLI's .glb passes Khronos's gltf-validator and decodes with draco3d to the .ply's triangles.
part node-export node_suite tests/export
part fuzz bash scripts/fuzz.sh
# The client library (clients/js: varints, frames, slot table, sessions, frames of the C++
# encoder) and the viewer's pure modules (clients/web/test).
part node-clients node --test clients/js/test/ clients/web/test/
# The viewer and its <isomesh-surface> element in Debian's chromium, served by a real isomesh-server on
# a free loopback port (tests/web: viewer, layout, embed, streaming, reconnect, expiry; screenshots in
# build/test-artifacts/web).
part browser node --test tests/web/
echo "test.sh: every part passed; wall and CPU time per part:"
printf '  %s\n' "${summary[@]}"
children_cpu
printf '%7d s  %5.0f s CPU  total\n' "$SECONDS" "$cpu_now"

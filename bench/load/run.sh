#!/usr/bin/env bash
# Load benchmark of isomesh-server on this machine (not part of the test command).
#
# 1. Starts build/bin/isomesh-server on a free loopback port and runs build/bin/isomesh-load with
#    200 sessions for 30 s (the viewer's gallery mix, sliders moving), printing its report.
# 2. Searches for the largest session count whose p99 time to first mesh stays under 100 ms:
#    doubling from 25 sessions, then bisecting, with shorter runs and a fresh server each time.
#    The search uses light_mix.json: the gallery surfaces whose first mesh takes a few ms on an
#    idle server (the tanglecube's and the gyroid's phase 1 alone take 80-100 ms here, so with
#    them no load at all would pass; step 1's report lists time to first mesh per surface).
#
# Settings (environment): SESSIONS (200), DURATION (30), SEARCH_DURATION (10), LIMIT_MS (100),
# MAX_SESSIONS (1000), THREADS (isomesh-load's I/O threads, 2), UPDATES_PER_S (of each slider
# session, 2), JITTER (isomesh-load --jitter: 0 asks every session of an entry for the same mesh,
# which the server's first-mesh cache may answer; 0.01 gives each session a mesh of its own),
# SERVER_ARGS (extra server flags, e.g. --first-mesh-cache 0 to measure without the cache),
# SEARCH (1; 0 skips step 2), MIX (mix file of step 1; empty: the built-in gallery mix),
# SEARCH_MIX (bench/load/light_mix.json), OUT (folder for the JSON reports, build/bench-load).
# Traffic stays on 127.0.0.1; every run is bounded in sessions and time.
set -euo pipefail
cd "$(dirname "$0")/../.."

SESSIONS=${SESSIONS:-200}
DURATION=${DURATION:-30}
SEARCH_DURATION=${SEARCH_DURATION:-10}
LIMIT_MS=${LIMIT_MS:-100}
MAX_SESSIONS=${MAX_SESSIONS:-1000}
THREADS=${THREADS:-2}
UPDATES_PER_S=${UPDATES_PER_S:-2}
JITTER=${JITTER:-0}
SERVER_ARGS=${SERVER_ARGS:-}
SEARCH=${SEARCH:-1}
MIX=${MIX:-}
SEARCH_MIX=${SEARCH_MIX:-bench/load/light_mix.json}
OUT=${OUT:-build/bench-load}
BIN=${BIN:-build/bin}
for program in isomesh-server isomesh-load; do
  [ -x "$BIN/$program" ] || { echo "no $BIN/$program: run scripts/build.sh first" >&2; exit 1; }
done
mkdir -p "$OUT"

server_pid=
server_log=$(mktemp)
stop_server() {
  if [ -n "$server_pid" ]; then
    kill -TERM "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
    server_pid=
  fi
}
trap 'stop_server; rm -f "$server_log"' EXIT

# Starts a fresh server; sets $port from its "listening" log line.
start_server() {
  stop_server
  # Sessions in memory only (each run starts afresh) unless SERVER_ARGS names a --store.
  local store_args=(--store none)
  case "$SERVER_ARGS" in *--store*) store_args=() ;; esac
  # shellcheck disable=SC2086  # SERVER_ARGS is a list of flags
  "$BIN/isomesh-server" --bind 127.0.0.1 --port 0 --log-level info "${store_args[@]}" $SERVER_ARGS \
    2>"$server_log" >/dev/null &
  server_pid=$!
  port=
  for _ in $(seq 200); do
    port=$(sed -n 's/.*"event":"listening".*"port":\([0-9]*\).*/\1/p' "$server_log" | head -1)
    [ -n "$port" ] && return 0
    kill -0 "$server_pid" 2>/dev/null || break
    sleep 0.05
  done
  echo "isomesh-server did not start:" >&2
  cat "$server_log" >&2
  exit 1
}

# run_load SESSIONS DURATION JSON [MIX]: one isomesh-load run against a fresh server; prints the
# table.
run_load() {
  local mix_args=()
  [ -n "${4:-}" ] && mix_args=(--mix "$4")
  start_server
  "$BIN/isomesh-load" --url "ws://127.0.0.1:$port/ws" --sessions "$1" --duration "$2" \
    --threads "$THREADS" --updates-per-s "$UPDATES_PER_S" --jitter "$JITTER" --json "$3" "${mix_args[@]}" ||
    true  # errors are in the report
  stop_server
}

# json_field FILE EXPR: a figure of a report, e.g. time_to_first_mesh_ms.p99.
json_field() {
  node -e 'const r = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8"));
           console.log(process.argv[2].split(".").reduce((o, k) => o[k], r));' "$1" "$2"
}

# holds N: true when N sessions keep p99 time to first mesh under LIMIT_MS without errors.
holds() {
  local json="$OUT/search-$1.json"
  run_load "$1" "$SEARCH_DURATION" "$json" "$SEARCH_MIX" >/dev/null
  local p99 errors
  p99=$(json_field "$json" time_to_first_mesh_ms.p99)
  errors=$(json_field "$json" errors.total)
  echo "  $1 sessions: p99 time to first mesh $p99 ms, $errors errors" >&2
  node -e 'process.exit(Number(process.argv[1]) < Number(process.argv[2]) && process.argv[3] === "0" ? 0 : 1)' \
    "$p99" "$LIMIT_MS" "$errors"
}

echo "== isomesh-load: $SESSIONS sessions for $DURATION s ($(nproc) cores)"
run_load "$SESSIONS" "$DURATION" "$OUT/load-$SESSIONS.json" "$MIX"
echo "(JSON report: $OUT/load-$SESSIONS.json)"

[ "$SEARCH" = 1 ] || exit 0
echo
echo "== largest session count with p99 time to first mesh < $LIMIT_MS ms"
echo "   ($SEARCH_DURATION s runs, mix $SEARCH_MIX)"
good=0
bad=
n=25
while [ "$n" -le "$MAX_SESSIONS" ]; do
  if holds "$n"; then good=$n; n=$((n * 2)); else bad=$n; break; fi
done
if [ -z "$bad" ]; then
  echo "holds at $good sessions, the largest tried (MAX_SESSIONS=$MAX_SESSIONS)"
  exit 0
fi
# Bisect between the last count that held and the first that did not, to within 10%.
while [ $((bad - good)) -gt $(( (good > 10 ? good : 10) / 10 )) ]; do
  mid=$(( (good + bad) / 2 ))
  if holds "$mid"; then good=$mid; else bad=$mid; fi
done
if [ "$good" = 0 ]; then
  echo "even 25 sessions miss the limit (see $OUT/search-25.json)"
else
  echo "largest session count with p99 time to first mesh < $LIMIT_MS ms: $good (fails at $bad)"
fi

#!/usr/bin/env bash
# The C++ suites (ctest) once more, built into build-asan/ with asserts compiled in
# (ISOMESH_ASSERTS: no NDEBUG, _GLIBCXX_ASSERTIONS) under AddressSanitizer and
# UndefinedBehaviorSanitizer (ISOMESH_SANITIZE: undefined behaviour aborts the test). Only the
# ctest suites and the programs they run are built: no benchmarks, fuzzers or Node suites
# (scripts/test.sh runs those against build/).
set -euo pipefail
cd "$(dirname "$0")/.."
# -O1 -g1: the sanitizers' usual optimisation level, with line tables for their stack traces, and
# faster to compile than RelWithDebInfo's -O2 -g.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DISOMESH_SANITIZE=ON -DISOMESH_ASSERTS=ON \
  -DISOMESH_BUILD_TESTS=ON -DISOMESH_BUILD_BENCH=OFF >/dev/null
# The test executables, and the programs the CLI and client tests run (tests/CMakeLists.txt).
tests=$(cmake --build build-asan --target help | sed -n 's/^\(test_[a-z_]*\): phony$/\1/p')
# shellcheck disable=SC2086
cmake --build build-asan -j "$(nproc)" --target $tests isomesh isomesh-server isomesh-load
echo "test-asan: built in $SECONDS s"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1
# Left out here (they run in build/), each among the slowest under the sanitizers while its code
# paths are those of faster tests run here too:
# - the Blobby cube tests (each over 20 s);
# - the pipeline's budget test on the genus-two surface at every budget and on the heart at
#   budgets 100 and 1,000 (each 25-80 s): the same test runs here on the torus, the tanglecube
#   and the gyroid at the same three budgets (simplification to the budget, refinement), and on
#   the heart at 20,000 (refinement near its singular point);
# - ServerHelp (two servers meshing bear.vm: 20-30 s in the release build): the helpers' code paths run here in
#   the Helpers, WorkerPool help and EvaluatorPool tests.
exclude='Blobby|ServerHelp|PipelineBudget\..*/(genus_two_[0-9]+|heart_100|heart_1000)$'
ctest --test-dir build-asan --output-on-failure -j "$(nproc)" --timeout 600 -E "$exclude"

#!/usr/bin/env bash
# Installs, builds with ASan+UBSan (-Werror) and runs the whole test suite,
# then fuzzes every parser of outside input for a bounded, reproducible run.
#
# One build, not two: every test runs under the sanitizers (the library at
# -O1; the test files, the CLI and the daemon at -O0), the browser and install
# tests included; the benchmarks and tools are compiled too (at -O0) so they
# cannot rot. A second, optimised build ran the same tests again without the
# sanitizers' checks, at a third of CI's 25-minute budget (docs/PERFORMANCE.md);
# the demo command builds Release.
#
# clang-tidy is not run here: its 400 CPU-s put the command over CI's budget
# on 2 cores (docs/PERFORMANCE.md, "Back inside the budget"). Run it on the
# build this leaves, before committing: bash tools/tidy.sh build/asan
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
jobs=$(nproc)
t0=$(date +%s)
lap() { echo "== $1 ($(($(date +%s) - t0)) s since the build started)"; }

lap "ASan+UBSan build (-Werror)"
# -g1: line-level stack traces at a fraction of -g's compile time.
cmake -S . -B build/asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
  -DCNCSTREAM_WERROR=ON -DCNCSTREAM_SANITIZE=ON -DCNCSTREAM_BUILD_TOOLS=ON
cmake --build build/asan -j"$jobs"

lap "ASan+UBSan tests"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure -j"$jobs" --timeout 1800

lap "Fuzzing (libFuzzer, clang, ASan+UBSan): saved regressions, then a bounded run of each target"
bash tools/fuzz.sh --ci

lap "all passed"

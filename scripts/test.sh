#!/usr/bin/env bash
# Installs, builds with ASan+UBSan (-Werror) and runs the whole test suite,
# fuzzes every parser for a bounded, reproducible run, and checks src/ and
# sim/ with clang-tidy (.clang-tidy; any finding fails).
#
# One build, not two: every test runs under the sanitizers (the library at
# -O1; the test files and the daemon at -O0), the browser and install tests
# included; the benchmarks and tools are compiled too so they cannot rot. A
# second, optimised build ran the same tests again without the sanitizers'
# checks, at a third of CI's 25-minute budget (docs/PERFORMANCE.md); the demo
# command builds Release.
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

lap "ASan+UBSan tests, with clang-tidy beside them at the lowest priority"
# clang-tidy over src/ and sim/ (.clang-tidy; about 400 CPU-s) takes the CPU
# time the tests leave idle while they wait on simulated machines and sockets;
# at nice 19 the tests come first (the step still takes longer: docs/PERFORMANCE.md). Its own session, so
# that a failing step stops it and its children too.
setsid nice -n 19 bash tools/tidy.sh build/asan >build/asan/tidy.log 2>&1 &
tidy_pid=$!
trap 'kill -- -"$tidy_pid" 2>/dev/null || true' EXIT
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure -j"$jobs" --timeout 1800

lap "Fuzzing (libFuzzer, clang, ASan+UBSan): saved regressions, then a bounded run of each target"
bash tools/fuzz.sh --ci

lap "clang-tidy (tools/tidy.sh): waiting for the rest of its run"
tidy_rc=0
wait "$tidy_pid" || tidy_rc=$?
trap - EXIT
cat build/asan/tidy.log
[[ $tidy_rc -eq 0 ]] || { echo "clang-tidy: findings above (exit $tidy_rc)"; exit 1; }

lap "all passed"

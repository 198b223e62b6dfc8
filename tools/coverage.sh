#!/usr/bin/env bash
# Line and branch coverage of the library (src/ without the apps, and sim/)
# by the whole test suite, with gcovr.
#   tools/coverage.sh [BUILD_DIR]     (default build/coverage)
# Builds the project at -O0 with --coverage (atomic counters: the CL engine,
# the daemon and the session run on several threads, and racing counters give
# gcov negative branch counts that gcovr refuses; no sanitizers, no benchmarks),
# runs every test, and writes BUILD_DIR/coverage/index.html (per file) and
# BUILD_DIR/coverage/summary.txt; prints the library's figures. The apps'
# own files (src/apps/) and the tests are left out of the figure: they are the
# front ends and the checks, not the library.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
build=${1:-build/coverage}
command -v gcovr >/dev/null || { echo "coverage: needs gcovr (Debian: gcovr)"; exit 2; }
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O0 -g0" \
  "-DCMAKE_CXX_FLAGS=--coverage -fprofile-update=atomic" -DCMAKE_EXE_LINKER_FLAGS=--coverage -DCNCSTREAM_BUILD_TOOLS=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" -j"$(nproc)"
find "$build" -name '*.gcda' -delete
# A failing test still gives a figure, but the script says so and fails.
tests=0
ctest --test-dir "$build" -j"$(nproc)" --timeout 1800 --output-on-failure >"$build/ctest.log" 2>&1 || tests=$?
tail -3 "$build/ctest.log"
mkdir -p "$build/coverage"
gcovr -r "$root" --object-directory "$build" -j "$(nproc)" \
  --filter "$root/src/" --filter "$root/sim/" --filter "$root/include/" --exclude "$root/src/apps/" \
  --exclude-throw-branches --exclude-unreachable-branches \
  --html-details "$build/coverage/index.html" --txt "$build/coverage/files.txt" \
  --print-summary >"$build/coverage/summary.txt"
cat "$build/coverage/summary.txt" | tail -3
echo "coverage: per file in $build/coverage/index.html and $build/coverage/files.txt"
((tests == 0)) || { echo "coverage: some tests failed (see $build/ctest.log)"; exit 1; }

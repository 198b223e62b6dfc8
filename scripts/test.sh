#!/usr/bin/env bash
# Installs, builds (Release with -Werror, then ASan+UBSan) and runs the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
jobs=$(nproc)

echo "== Release build (-Werror)"
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCNCSTREAM_WERROR=ON
cmake --build build/release -j"$jobs"
echo "== Release tests"
ctest --test-dir build/release --output-on-failure -j"$jobs" --timeout 900

echo "== ASan+UBSan build"
# -O1 -g1 with assertions on: line-level stack traces, half the compile time of -O2 -g.
cmake -S . -B build/asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
  -DCNCSTREAM_WERROR=ON -DCNCSTREAM_SANITIZE=ON -DCNCSTREAM_BUILD_TOOLS=OFF
cmake --build build/asan -j"$jobs"
echo "== ASan+UBSan tests"
# The browser test (Chromium drives the page against cncstreamd) and the
# install test (copies the build into a prefix) ran in the Release build:
# under ASan they add two minutes and check nothing about memory the daemon
# API tests do not.
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure -j"$jobs" --timeout 1800 -E '^(Web|Install)\.'

#!/usr/bin/env bash
# The long soak under faults (issue 16, docs/reliability.md): a million
# numbered lines streamed to the simulator while it injects every fault it
# can at points drawn from a fixed seed, with override changes and hold/resume
# cycles; every fault that ends a job is answered as an operator would and
# the job resumed from the journal. It is the test suite's Soak test at full
# size, so it builds nothing: give it the build folder (target test_reliability).
#   tools/soak.sh BUILD_DIR [LINES=1000000] [FAULTS=60] [SEED=16]
# Prints lines/s, the faults injected, resident memory (start/end/max) and
# every job with the fault that ended it; exits 1 if any check failed.
set -euo pipefail
build=${1:?usage: tools/soak.sh BUILD_DIR [LINES] [FAULTS] [SEED]}
bin="$build/test_reliability"
[[ -x $bin ]] || { echo "soak: no $bin; build the test_reliability target first" >&2; exit 2; }
log=$(mktemp /tmp/cncstream_soak.XXXXXX.log)
start=$(date +%s)
set +e
CNCSOAK_LINES=${2:-1000000} CNCSOAK_FAULTS=${3:-60} CNCSOAK_SEED=${4:-16} \
  "$bin" --gtest_filter='Soak.*' >"$log" 2>&1
code=$?
set -e
grep '^soak: ' "$log" | grep -v '^soak: job \|^soak:   ' || true
echo "soak: jobs (resumed after line, planned fault -> outcome, last answered line, answered lines the simulator did not run | report):"
grep '^soak: job \|^soak:   ' "$log" | cut -c7-220 || true
if [[ $code -ne 0 ]]; then
  sed -n '/Failure\|exception/,+12p' "$log"
  echo "soak: FAILED after $(( $(date +%s) - start )) s (full log: $log)"
  exit 1
fi
echo "soak: passed in $(( $(date +%s) - start )) s"
rm -f "$log"

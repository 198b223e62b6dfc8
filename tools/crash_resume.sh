#!/usr/bin/env bash
# Crash at any moment (issue 16, docs/reliability.md): `cncstream` streaming a
# finishing job to `cncsim` through its pty is killed with SIGKILL at KILLS
# moments drawn from a fixed seed, and resumed from the journal each time;
# then the simulator itself is killed mid-job and the job finished on a fresh
# one started from its saved state. Each time the final machined surface is
# compared with an uninterrupted run's. It is the test suite's CrashResume
# tests with more kills, so it builds nothing: give it the build folder
# (targets test_reliability, cncstream, cncsim).
#   tools/crash_resume.sh BUILD_DIR [KILLS=20] [SEED=16]
set -euo pipefail
build=${1:?usage: tools/crash_resume.sh BUILD_DIR [KILLS] [SEED]}
for b in test_reliability cncstream cncsim; do
  [[ -x $build/$b ]] || { echo "crash: no $build/$b; build it first" >&2; exit 2; }
done
log=$(mktemp /tmp/cncstream_crash.XXXXXX.log)
start=$(date +%s)
set +e
CNCCRASH_KILLS=${2:-20} CNCCRASH_SEED=${3:-16} "$build/test_reliability" --gtest_filter='CrashResume.*' >"$log" 2>&1
code=$?
set -e
grep '^crash: ' "$log" || true
if [[ $code -ne 0 ]]; then
  sed -n '/Failure\|exception/,+12p' "$log"
  echo "crash: FAILED after $(( $(date +%s) - start )) s (full log: $log)"
  exit 1
fi
echo "crash: passed in $(( $(date +%s) - start )) s"
rm -f "$log"

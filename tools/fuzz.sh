#!/usr/bin/env bash
# Fuzzes every parser of outside input with libFuzzer (clang, ASan + UBSan).
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
# Builds tests/fuzz into build/fuzz, replays every saved regression input
# (tests/fuzz/regressions/<target>/), then runs each target for SECONDS (60
# by default) from its seeds: tests/fuzz/corpus/<target>/ plus the inputs the
# project already has (examples/, ../shared/meshes, firmware-profiles/, a
# journal written for the purpose). A crash, hang, leak or sanitizer report
# fails the run and leaves the input in build/fuzz/findings/<target>/: fix the
# bug, then save the input under tests/fuzz/regressions/<target>/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
secs=${1:-60}
shift || true
build=build/fuzz
cmake -S tests/fuzz -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None >/dev/null
cmake --build "$build" -j"$(nproc)"

all=(fuzz_stl fuzz_gcode fuzz_grbl_answers fuzz_marlin_answers fuzz_profile fuzz_journal)
targets=("${@:-${all[@]}}")
shared=${CNCSTREAM_SHARED_MESHES_DIR:-$root/../shared/meshes}

seed() {  # seed TARGET DIR: the seeds the project already has
  local t=$1 d=$2
  mkdir -p "$d"
  [[ -d tests/fuzz/corpus/$t ]] && cp -f tests/fuzz/corpus/"$t"/* "$d"/ 2>/dev/null || true
  case $t in
    fuzz_stl)
      for f in "$shared"/parser-fixtures/* "$shared"/defects/*; do
        [[ -f $f && $(stat -c %s "$f") -le 70000 ]] && cp -f "$f" "$d"/
      done ;;
    fuzz_profile) cp -f firmware-profiles/*.toml "$d"/ ;;
    fuzz_journal) "$build"/make_journal_seed "$d"/seed.sqlite ;;
  esac
}

status=0
report=$build/report.txt
: >"$report"
for t in "${targets[@]}"; do
  bin=$build/$t
  [[ -x $bin ]] || { echo "fuzz: no target $t"; exit 2; }
  findings=$build/findings/$t
  mkdir -p "$findings"
  regressions=(tests/fuzz/regressions/"$t"/*)
  if [[ -e ${regressions[0]} ]]; then
    echo "== $t: ${#regressions[@]} regression input(s)"
    if ! ASAN_OPTIONS=detect_leaks=1 "$bin" -timeout=10 "${regressions[@]}" >"$findings/regressions.log" 2>&1; then
      echo "fuzz: $t fails on a saved regression input:"; tail -30 "$findings/regressions.log"; status=1
    fi
  fi
  corpus=$build/corpus/$t
  seed "$t" "$corpus"
  max_len=8192
  [[ $t == fuzz_stl || $t == fuzz_journal ]] && max_len=70000
  echo "== $t: fuzzing for ${secs} s"
  if ASAN_OPTIONS=detect_leaks=1 "$bin" "$corpus" -max_total_time="$secs" -max_len="$max_len" -timeout=10 \
       -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 >"$findings/run.log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$findings/run.log" | grep -o '[0-9]*$' || echo "?")
    cov=$(grep -o 'cov: [0-9]*' "$findings/run.log" | tail -1 | grep -o '[0-9]*' || echo "?")
    printf '%-22s %6s s  %10s runs  coverage %6s  no finding\n' "$t" "$secs" "$runs" "$cov" | tee -a "$report"
  else
    echo "fuzz: $t found a problem (input in $findings/):"; grep -E "ERROR|SUMMARY|runtime error|Test unit written" "$findings/run.log" | head -10
    printf '%-22s FOUND A PROBLEM: see %s\n' "$t" "$findings/run.log" >>"$report"
    status=1
  fi
done
echo "fuzz: report in $report"
exit $status

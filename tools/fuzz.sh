#!/usr/bin/env bash
# Fuzzes every parser of outside input with libFuzzer (clang, ASan + UBSan).
#   tools/fuzz.sh [--ci] [SECONDS_PER_TARGET] [TARGET...]
# Builds tests/fuzz into build/fuzz (only the targets asked for, all cores,
# ccache when there is one), replays every saved regression input
# (tests/fuzz/regressions/<target>/), then runs each target for SECONDS, one per core at a time, (60
# by default, or $FUZZ_SECONDS) from its seeds: tests/fuzz/corpus/<target>/
# plus the inputs the project already has (examples/, ../shared/meshes,
# firmware-profiles/, tests/pendant/fixtures/, a journal written for the
# purpose) and what earlier runs added in build/fuzz/corpus/<target>/. A
# crash, hang, leak or sanitizer report fails the run and leaves the input in
# build/fuzz/findings/<target>/: fix the bug, then save the input under
# tests/fuzz/regressions/<target>/.
#
# --ci: the bounded run for the test command: 10 s per target unless
# SECONDS or $FUZZ_SECONDS says otherwise, and the build's and the runs' times
# printed at the end. Exits 1 on any finding, 2 when it cannot build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
ci=0
if [[ ${1:-} == --ci ]]; then
  ci=1
  shift
fi
secs=${FUZZ_SECONDS:-$((ci ? 10 : 60))}
if [[ ${1:-} =~ ^[0-9]+$ ]]; then
  secs=$1
  shift
fi
build=build/fuzz
all=(fuzz_stl fuzz_gcode fuzz_grbl_answers fuzz_marlin_answers fuzz_profile fuzz_journal
     fuzz_http_request fuzz_ws_message fuzz_job_params fuzz_daemon_config fuzz_pendant_report)
targets=("${@:-${all[@]}}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz: no target $t (targets: ${all[*]})"; exit 2; }
done
shared=${CNCSTREAM_SHARED_MESHES_DIR:-$root/../shared/meshes}

command -v clang++ >/dev/null || { echo "fuzz: needs clang++ (Debian: clang, libclang-rt-14-dev)"; exit 2; }
t0=$(date +%s)
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
build_targets=("${targets[@]}")
[[ " ${targets[*]} " == *" fuzz_journal "* ]] && build_targets+=(make_journal_seed)
if ! { cmake -S tests/fuzz -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None "${launcher[@]}" >/dev/null &&
       cmake --build "$build" -j"$(nproc)" --target "${build_targets[@]}"; }; then
  echo "fuzz: the build failed"
  exit 2
fi
t1=$(date +%s)

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
    fuzz_pendant_report) cp -f tests/pendant/fixtures/*.txt "$d"/ ;;
  esac
}

report=$build/report.txt
: >"$report"
run_target() {  # run_target TARGET: its regression inputs, then SECONDS of fuzzing; 1 on a finding
  local t=$1 bin=$build/$1 findings=$build/findings/$1 corpus=$build/corpus/$1 status=0 runs cov max_len=8192
  mkdir -p "$findings"
  local regressions=(tests/fuzz/regressions/"$t"/*)
  if [[ -e ${regressions[0]} ]]; then
    echo "== $t: ${#regressions[@]} regression input(s)"
    if ! ASAN_OPTIONS=detect_leaks=1 "$bin" -timeout=10 "${regressions[@]}" >"$findings/regressions.log" 2>&1; then
      echo "fuzz: $t fails on a saved regression input:"; tail -30 "$findings/regressions.log"; status=1
    fi
  fi
  seed "$t" "$corpus"
  [[ $t == fuzz_stl || $t == fuzz_journal ]] && max_len=70000
  echo "== $t: fuzzing for ${secs} s"
  if ASAN_OPTIONS=detect_leaks=1 "$bin" "$corpus" -max_total_time="$secs" -max_len="$max_len" -timeout=10 \
       -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 >"$findings/run.log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$findings/run.log" | grep -o '[0-9]*$' || echo "?")
    cov=$(grep -o 'cov: [0-9]*' "$findings/run.log" | tail -1 | grep -o '[0-9]*' || echo "?")
    printf '%-22s %6s s  %10s runs  coverage %6s  no finding\n' "$t" "$secs" "$runs" "$cov" >>"$report"
  else
    echo "fuzz: $t found a problem (input in $findings/):"; grep -E "ERROR|SUMMARY|runtime error|Test unit written" "$findings/run.log" | head -10
    printf '%-22s FOUND A PROBLEM: see %s\n' "$t" "$findings/run.log" >>"$report"
    status=1
  fi
  echo "$status" >"$findings/status"
}

# One target per core at a time (each libFuzzer process is single-threaded).
for t in "${targets[@]}"; do
  while (($(jobs -rp | wc -l) >= $(nproc))); do wait -n || true; done
  rm -f "$build/findings/$t/status"
  run_target "$t" &
done
wait
status=0
for t in "${targets[@]}"; do
  [[ $(cat "$build/findings/$t/status" 2>/dev/null) == 0 ]] || status=1
done
sort -o "$report" "$report"
cat "$report"
t2=$(date +%s)
echo "fuzz: report in $report"
if ((ci)); then
  echo "fuzz: build $((t1 - t0)) s, ${#targets[@]} targets run in $((t2 - t1)) s ($secs s each)" | tee -a "$report"
fi
exit $status

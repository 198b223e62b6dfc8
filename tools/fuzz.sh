#!/usr/bin/env bash
# Fuzzes every parser of outside input with libFuzzer (clang, ASan + UBSan).
#   tools/fuzz.sh [--ci] [SECONDS_PER_TARGET] [TARGET...]
# Builds tests/fuzz into build/fuzz (only the targets asked for, all cores,
# ccache when there is one), replays every saved regression input
# (tests/fuzz/regressions/<target>/), then runs each target, one per core at
# a time, for SECONDS (60 by default, or $FUZZ_SECONDS) from its seeds: tests/fuzz/corpus/<target>/
# plus the inputs the project already has (examples/, ../shared/meshes,
# firmware-profiles/, tests/pendant/fixtures/, a journal written for the
# purpose) and what earlier runs added in build/fuzz/corpus/<target>/. A
# crash, hang, leak or sanitizer report fails the run and leaves the input in
# build/fuzz/findings/<target>/: fix the bug, then save the input under
# tests/fuzz/regressions/<target>/.
#
# --ci: the bounded run for the test command, reproducible: each target runs
# a fixed number of inputs from a fixed seed (about 5 s each on the 2-core
# machine; 60 s at most), so a CI run finds only what the sources changed
# make findable, never a random old bug; the build's and the runs' times are
# printed at the end. The open-ended search is the run without --ci.
# Exits 1 on any finding, 2 when it cannot build.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
ci=0
if [[ ${1:-} == --ci ]]; then
  ci=1
  shift
fi
secs=${FUZZ_SECONDS:-60}
if [[ ${1:-} =~ ^[0-9]+$ ]]; then
  secs=$1
  shift
fi
build=build/fuzz
all=(fuzz_stl fuzz_gcode fuzz_grbl_answers fuzz_marlin_answers fuzz_profile fuzz_journal
     fuzz_http_request fuzz_ws_message fuzz_job_params fuzz_daemon_config fuzz_pendant_report)
targets=("${@:-${all[@]}}")
# --ci: inputs per target, about 5 s of each at the rates measured (docs/reliability.md).
declare -A ci_runs=([fuzz_stl]=30000 [fuzz_gcode]=1500 [fuzz_grbl_answers]=700 [fuzz_marlin_answers]=1400
  [fuzz_profile]=1000 [fuzz_journal]=800 [fuzz_http_request]=20000 [fuzz_ws_message]=40000
  [fuzz_job_params]=50000 [fuzz_daemon_config]=35000 [fuzz_pendant_report]=20000)
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
  local start
  start=$(date +%s)
  mkdir -p "$findings"
  local regressions=(tests/fuzz/regressions/"$t"/*)
  if [[ -e ${regressions[0]} ]]; then
    echo "== $t: ${#regressions[@]} regression input(s)"
    if ! ASAN_OPTIONS=detect_leaks=1 "$bin" -timeout=10 "${regressions[@]}" >"$findings/regressions.log" 2>&1; then
      echo "fuzz: $t fails on a saved regression input:"; tail -30 "$findings/regressions.log"; status=1
    fi
  fi
  if ((ci)); then  # the seeds alone, not what earlier runs added: the same run every time
    corpus=$build/ci-corpus/$t
    rm -rf "$corpus"
  fi
  seed "$t" "$corpus"
  [[ $t == fuzz_stl || $t == fuzz_journal ]] && max_len=70000
  local bound=(-max_total_time="$secs")
  if ((ci)); then
    bound=(-runs="${ci_runs[$t]}" -seed=16 -max_total_time=60)
    echo "== $t: fuzzing ${ci_runs[$t]} inputs from seed 16"
  else
    echo "== $t: fuzzing for ${secs} s"
  fi
  if ASAN_OPTIONS=detect_leaks=1 "$bin" "$corpus" "${bound[@]}" -max_len="$max_len" -timeout=10 \
       -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 >"$findings/run.log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$findings/run.log" | grep -o '[0-9]*$' || echo "?")
    cov=$(grep -o 'cov: [0-9]*' "$findings/run.log" | tail -1 | grep -o '[0-9]*' || echo "?")
    printf '%-22s %6s s  %10s runs  coverage %6s  no finding\n' "$t" "$(($(date +%s) - start))" "$runs" "$cov" >>"$report"
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
  echo "fuzz: build $((t1 - t0)) s, ${#targets[@]} targets run in $((t2 - t1)) s" | tee -a "$report"
fi
exit $status

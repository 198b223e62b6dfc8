#!/usr/bin/env bash
# How fast the default programs can stream over a 115,200-baud link: the
# plaque's default finishing, the README's main job and every shared mesh
# scaled to about 100 mm, with arcs on and off. For each: lines, generation
# time, and ../shared/tools/streamable.py's worst 50-move window (the feed
# the densest stretch arrives in time for) and its figures at F3000.
# Usage: tools/bench_streamable.sh BUILD_DIR [OUT_DIR]
set -euo pipefail
build=${1:?usage: bench_streamable.sh BUILD_DIR [OUT_DIR]}
out=${2:-$(mktemp -d)}
here="$(cd "$(dirname "$0")/.." && pwd)"
shared="$here/../shared"
streamable="$shared/tools/streamable.py"
mkdir -p "$out"
run() {  # NAME ARGS...
  local name=$1; shift
  for arcs in on off; do
    local nc="$out/$name-arcs-$arcs.nc"
    local t0=$(date +%s.%N)
    "$build/cncstream" toolpath "$@" --arcs "$arcs" --feed 3000 -o "$nc" > /dev/null
    local t=$(echo "$(date +%s.%N) - $t0" | bc)
    local lines=$(wc -l < "$nc")
    local s=$(python3 "$streamable" "$nc" | sed -n 's/.*worst \([0-9]*\) mm\/min.*/\1/p')
    local f=$(python3 "$streamable" "$nc" | sed -n 's/.*at its own feeds: \(.*\)/\1/p')
    printf '%-28s arcs %-3s %8s lines %6.2f s  worst window %6s mm/min  at F3000: %s\n' "$name" "$arcs" "$lines" "$t" "$s" "$f"
  done
}
run plaque-default "$here/examples/plaque.stl" --tool ball:3.175
run plaque-main-job "$here/examples/plaque.stl" --tool ball:3.175 --rough flat:6 --scallop 0.05
run gearwheel "$shared/meshes/gearwheel.bin.stl" --tool ball:3.175 --scale 2.4
run lion-head "$shared/meshes/lion_head_relief.stl" --tool ball:3.175 --scale 100
run fandisk "$shared/meshes/fandisk.stl" --tool ball:3.175 --scale 100
run housing "$shared/meshes/tr12j_housing_occt.stl" --tool ball:3.175 --scale 0.2

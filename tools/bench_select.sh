#!/usr/bin/env bash
# Cutter-selection report benchmark: `cncstream select` on the plaque at 0.4 mm
# stepover and 0.05 mm along the rows (two CL grids, two raster paths, the
# cut simulation of both, maps and numbers), three runs, with the phases.
# Usage: tools/bench_select.sh [build-dir]   (Release build)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build/release}/cncstream"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for run in 1 2 3; do
  /usr/bin/time -f "%e s wall, %U s user, %M KB peak" "$bin" select examples/plaque.stl \
    --tools ball:3.175,bull:3.175:0.79 --stepover 0.4 --step 0.05 -o "$out/report" > "$out/report.txt" 2> "$out/time.txt"
  echo "run $run: $(tail -1 "$out/time.txt"); $(grep '^time:' "$out/report.txt")"
done

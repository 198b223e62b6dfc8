#!/usr/bin/env bash
# End-to-end tool-path benchmark: load, CL grid, path, G-code written, as the
# operator runs it. Usage: tools/bench_toolpath.sh [build-dir]   (Release build)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build/release}/cncstream"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for tool in ball:3.175 flat:3.175 bull:3.175:0.79; do
  for run in 1 2 3; do
    /usr/bin/time -f "%e s wall, %M KB peak" "$bin" toolpath examples/plaque.stl --tool "$tool" \
      --stepover 0.4 --step 0.05 -o "$out/plaque.nc" > "$out/report.txt" 2> "$out/time.txt"
    echo "$tool run $run: $(tail -1 "$out/time.txt"), $(grep '^G-code' "$out/report.txt")"
  done
done

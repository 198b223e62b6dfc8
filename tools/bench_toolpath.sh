#!/usr/bin/env bash
# End-to-end tool-path benchmark: load, CL grid, path, G-code written, as the
# operator runs it. Usage: tools/bench_toolpath.sh [build-dir]   (Release build)
#
# 1. The finishing alone (steep-and-shallow, the default; --stock none: no
#    roughing, no depth check), 0.4 mm stepover, 0.05 mm step, per cutter.
#    (Without --stock none a flat:3.175 finishing would need a roughing that
#    cannot keep it within its 0.79 mm depth, and the job refuses.)
# 2. The complete job from the block (issue 12's target, <= 3 s): Z-level
#    roughing with flat:6, steep-and-shallow finishing with ball:3.175 at a
#    0.05 mm scallop, tolerance 0.02 mm.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build/release}/cncstream"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {
  /usr/bin/time -f "%e s wall, %U s user, %M KB peak" "$bin" toolpath examples/plaque.stl "$@" -o "$out/plaque.nc" \
    > "$out/report.txt" 2> "$out/time.txt"
  echo "$(tail -1 "$out/time.txt"), $(grep '^G-code:' "$out/report.txt" | cut -d, -f1)"
}
for tool in ball:3.175 flat:3.175 bull:3.175:0.79; do
  for n in 1 2 3; do
    echo "finishing $tool run $n: $(run --tool "$tool" --stepover 0.4 --step 0.05 --stock none)"
  done
done
for n in 1 2 3 4 5; do
  echo "complete job run $n: $(run --tool ball:3.175 --rough flat:6 --scallop 0.05 --tolerance 0.02)"
done

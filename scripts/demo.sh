#!/usr/bin/env bash
# Installs what is missing, builds Release and runs the main job: the operator's command on the example part,
# streamed to the built-in GRBL simulator (PORT=sim), which cuts a stock and checks it against the design.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc)" --target cncstream cncsim
mkdir -p out
echo "== cncstream examples/plaque.stl sim: finishing path, plan, stream to the simulator, verify the cut"
./build/release/cncstream examples/plaque.stl sim --tool ball:3.175 --stepover 0.4 --yes \
  --journal out/journal.sqlite -o out/plaque.nc --sim-png out/plaque-deviation.png
echo "== The journal"
./build/release/cncstream jobs --journal out/journal.sqlite
echo "== CL surface as a height map"
./build/release/cncstream clgrid examples/plaque.stl --tool ball:3.175 --grid 0.1 -o out/plaque-cl.png
echo "Outputs in out/: plaque.nc (the program), plaque-deviation.png (machined vs design), plaque-cl.png, journal.sqlite"

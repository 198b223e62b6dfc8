#!/usr/bin/env bash
# Installs what is missing, builds Release and runs the main job: the operator's command on the example part,
# streamed to the built-in GRBL simulator (PORT=sim), which cuts a stock and checks it against the design.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc)" --target cncstream cncsim
mkdir -p out
echo "== cncstream examples/plaque.stl sim: roughing and finishing paths, plan, stream to the simulator (tool change included), verify the cut"
./build/release/cncstream examples/plaque.stl sim --tool ball:3.175 --rough flat:6 --scallop 0.05 --tolerance 0.01 --yes \
  --sim-tool-table 1=flat:6@30,2=ball:3.175@37.3 \
  --journal out/journal.sqlite -o out/plaque.nc --sim-png out/plaque-deviation.png --sim-result out/plaque-cut.f32
echo "== The 3-D viewer, one frame each without a window: the program on the part, the simulated cut"
./build/release/cncstream view examples/plaque.stl --program out/plaque.nc --colour operation \
  --screenshot out/plaque-program.png --view iso
./build/release/cncstream view --cut out/plaque-cut.f32 --design examples/plaque.stl \
  --screenshot out/plaque-cut.png --view iso
echo "== The journal"
./build/release/cncstream jobs --journal out/journal.sqlite
echo "== CL surface as a height map"
./build/release/cncstream clgrid examples/plaque.stl --tool ball:3.175 --grid 0.1 -o out/plaque-cl.png
echo "Outputs in out/: plaque.nc (the program), plaque-deviation.png (machined vs design), plaque-program.png and plaque-cut.png (the viewer), plaque-cl.png, journal.sqlite"

#!/usr/bin/env bash
# Installs, builds Release and runs the main job on the example part.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build/release -j"$(nproc)" --target cncstream
mkdir -p out
echo "== Finishing tool path for examples/plaque.stl"
./build/release/cncstream toolpath examples/plaque.stl --tool ball:3.175 --stepover 0.4 --step 0.05 \
  --feed 1500 --plunge-feed 400 --rpm 18000 -o out/plaque.nc
echo "== CL grid height map"
./build/release/cncstream clgrid examples/plaque.stl --tool ball:3.175 --grid 0.2 -o out/plaque-cl.csv

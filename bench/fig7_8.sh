#!/usr/bin/env bash
# Mesit & Guha figures 7 and 8, reproduced: the 10k-face scene (examples/fig7_10k_faces.json: eight
# 1,280-face balls pressed together), steps 1–2000 (the paper's "frames": one simulation step
# each), sbhash, spatialhash and bvh one after the other in the same run, from the same state.
# Writes bench/results/fig7_8.csv (per step), fig7_8.txt (the report) and fig7_8.svg (the chart).
#   bench/fig7_8.sh [BUILD_DIR] [THREADS]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build}
threads=${2:-2}
out=bench/results
{
  echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, $threads threads, $(date -u +%F)"
  "$build/cli/softbake" bench examples/fig7_10k_faces.json --steps 2000 \
    --broadphase sbhash,spatialhash,bvh --threads "$threads" --csv "$out/fig7_8.csv"
} | tee "$out/fig7_8.txt"
python3 bench/plot_bench.py fig7_8 "$out/fig7_8.csv" "$out/fig7_8.svg"

#!/usr/bin/env bash
# Mesit & Guha figures 7 and 8, reproduced: the 10k-face scene (examples/fig7_10k_faces.json: eight
# 1,280-face balls pressed together), steps 1–2000 (the paper's "frames": one simulation step
# each), sbhash, spatialhash and bvh one after the other in the same run, from the same state.
# The broad phases run every step (--no-pair-cache), as the paper compares them; a second run with
# the pair cache (the default) shows what a user gets. Writes bench/results/fig7_8{,_cached}.csv
# (per step), .txt (the reports) and .svg (the charts).
#   bench/fig7_8.sh [BUILD_DIR] [THREADS]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build}
threads=${2:-2}
out=bench/results
for variant in "" _cached; do
  flags=--no-pair-cache
  [ -n "$variant" ] && flags=
  {
    echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, $threads threads, $(date -u +%F)"
    # shellcheck disable=SC2086  # $flags is empty or one flag
    "$build/cli/softbake" bench examples/fig7_10k_faces.json --steps 2000 $flags \
      --broadphase sbhash,spatialhash,bvh --threads "$threads" --csv "$out/fig7_8$variant.csv"
  } | tee "$out/fig7_8$variant.txt"
  python3 bench/plot_bench.py fig7_8 "$out/fig7_8$variant.csv" "$out/fig7_8$variant.svg"
done

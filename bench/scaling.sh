#!/usr/bin/env bash
# Scaling: the built-in balls scenes at 1k, 10k, 100k and 1M faces (more and finer balls, in
# contact from the first steps), every broad phase, and Bullet's btSoftBody on the same scenes.
# Writes bench/results/scaling.csv (one row per run), scaling.txt (the reports) and scaling.svg.
#   bench/scaling.sh [BUILD_DIR] [THREADS] [SIZES...]     (sizes: 1k 10k 100k 1m)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build}
threads=${2:-2}
shift $(($# < 2 ? $# : 2))
sizes=("${@:-1k 10k 100k 1m}")
read -r -a sizes <<<"${sizes[*]}"
out=bench/results
warmup=100  # the balls start 2 mm apart: contacts begin within ~50 steps at every size
declare -A steps=([1k]=1000 [10k]=500 [100k]=100 [1m]=20)

echo "scene,faces,broadphase,threads,steps,steps_per_s,median_step_ms,p95_step_ms,contacts_per_step,peak_rss_mb,bytes_per_face" >"$out/scaling.csv.tmp"
# key=value line -> the CSV columns above
to_csv() {
  python3 -c '
import sys
cols = "scene faces broadphase threads steps steps_per_s median_step_ms p95_step_ms contacts_per_step peak_rss_mb bytes_per_face".split()
for line in sys.stdin:
    kv = dict(p.split("=", 1) for p in line.split() if "=" in p)
    if "steps_per_s" in kv:
        print(",".join(kv.get(c, "") for c in cols))'
}
{
  echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, $threads threads, $(date -u +%F)"
  for size in "${sizes[@]}"; do
    scene=balls$size
    "$build/cli/softbake" bench "$scene" --warmup $warmup --steps "${steps[$size]}" \
      --broadphase sbhash,spatialhash,bvh --threads "$threads"
    if [ -x "$build/bench/bullet_peer_bench" ]; then
      "$build/bench/bullet_peer_bench" "$scene" --warmup $warmup --steps "${steps[$size]}" |
        sed 's/^peer=bullet /broadphase=bullet threads=1 /'
    fi
  done
} | tee "$out/scaling.txt" | tee >(grep --line-buffered 'steps_per_s=' | to_csv >>"$out/scaling.csv.tmp")
sleep 1
mv "$out/scaling.csv.tmp" "$out/scaling.csv"
python3 bench/plot_bench.py scaling "$out/scaling.csv" "$out/scaling.svg"

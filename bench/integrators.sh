#!/usr/bin/env bash
# Simulated frames per second of wall time, per integrator and beside the peers, on the same
# scenes in one run: what bench/results/integrators.md records.
#   bash bench/integrators.sh [BUILD_DIR] > bench/results/integrators.txt
# Scenes: balls10k (8 balls in two layers, in contact), bench/scenes/balls10k_falling_apart.json
# (8 balls that never touch each other, onto the ground) and examples/fig7_10k_faces.json. Each
# softbake run is the whole scene frame by frame as `run` does (`bench --frames`), simulation only.
# Each peer runs at its own usual settings, never at softbake's step count: Bullet at 10 substeps a
# frame, with its result's quality measured beside its speed (how deep it sinks into the ground,
# its bodies' volume, the intersecting triangle pairs between its bodies:
# bench/bullet_peer_bench.cpp, which also says where the two differ); Blender cloth at its quality 5
# (bench/blender_peer.sh installs Blender when it is missing; SOFTBAKE_NO_BLENDER=1 skips it).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
softbake=$build/cli/softbake
field() { sed -n "s/.*\b$1=\([^ ]*\).*/\1/p"; }
divide() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }

printf '| scene | integrator or peer | substeps/frame | steps/s | simulated frames/s | CG iterations/step | max abs(V/V_rest - 1) | max depth below the ground (m) | max intersecting pairs between bodies |\n'
printf '|---|---|---:|---:|---:|---:|---:|---:|---:|\n'
softbake_row() {  # scene name, label, then bench arguments; prints the row, sets $steps
  local scene=$1 name=$2 label=$3 line
  shift 3
  line=$("$softbake" bench "$scene" --frames "$frames" "$@" | tail -1)
  steps=$(field steps <<<"$line")
  printf '| %s | softbake %s | %s | %s | %s | %s | %s | – | – |\n' "$name" "$label" \
    "$(divide "$steps" $((frames - 1)))" "$(field steps_per_s <<<"$line")" \
    "$(field frames_per_s <<<"$line")" "$(field solver_iterations_per_step <<<"$line")" \
    "$(field max_volume_error <<<"$line")"
}
for scene in balls10k "$root/bench/scenes/balls10k_falling_apart.json" \
             "$root/examples/fig7_10k_faces.json"; do
  name=$(basename "$scene" .json)
  frames=$("$softbake" scene "$scene" | python3 -c 'import json,sys; print(json.load(sys.stdin)["settings"]["frames"])')
  frames=$((frames < 48 ? frames : 48))
  softbake_row "$scene" "$name" implicit --integrator implicit
  # The peers are compared at the first setting that keeps the balls round (Jolt: 4 collision
  # steps of 5 iterations): for backward Euler that is one substep a frame, where nothing touches.
  [ "$name" = balls10k_falling_apart ] &&
    softbake_row "$scene" "$name" "implicit, 1 substep a frame" --integrator implicit --substeps 1
  softbake_row "$scene" "$name" explicit --integrator explicit
  softbake_row "$scene" "$name" xpbd --integrator xpbd
  line=$("$build/bench/bullet_peer_bench" "$scene" --frames "$frames" --substeps-per-frame 10 | tail -1)
  printf '| %s | Bullet btSoftBody, 1 thread | 10 | %s | %s | – | %s | %s | %s |\n' "$name" \
    "$(field steps_per_s <<<"$line")" "$(field frames_per_s <<<"$line")" \
    "$(field max_volume_error <<<"$line")" "$(field max_penetration_m <<<"$line")" \
    "$(field max_pairs_between_bodies <<<"$line")"
  if [ -z "${SOFTBAKE_NO_BLENDER:-}" ]; then
    line=$(SOFTBAKE="$softbake" bash "$root/bench/blender_peer.sh" "$scene" --frames "$frames" 2>/dev/null | tail -1)
    printf '| %s | Blender 3.4 cloth, quality 5 | 5 | – | %s | – | – | – | – |\n' "$name" "$(field frames_per_s <<<"$line")"
  fi
done

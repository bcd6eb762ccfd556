#!/usr/bin/env bash
# Simulated frames per second of wall time, per integrator and beside the peers, on the same
# scenes in one run: what bench/results/integrators.md records.
#   bash bench/integrators.sh [BUILD_DIR] > bench/results/integrators.txt
# Scenes: balls10k (8 balls in two layers, in contact), bench/scenes/balls10k_falling_apart.json
# (8 balls that never touch each other, onto the ground) and examples/fig7_10k_faces.json. Each
# softbake run is the whole scene frame by frame as `run` does (`bench --frames`), simulation only.
# Bullet runs as many steps as softbake's default integrator takes for the same frames
# (bench/bullet_peer_bench.cpp says where the two differ); Blender cloth at its quality 5
# (bench/blender_peer.sh installs Blender when it is missing; SOFTBAKE_NO_BLENDER=1 skips it).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
softbake=$build/cli/softbake
field() { sed -n "s/.*\b$1=\([^ ]*\).*/\1/p"; }
divide() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }

printf '| scene | integrator or peer | substeps/frame | steps/s | simulated frames/s | CG iterations/step | max abs(V/V_rest - 1) |\n'
printf '|---|---|---:|---:|---:|---:|---:|\n'
softbake_row() {  # scene name, label, then bench arguments; prints the row, sets $steps
  local scene=$1 name=$2 label=$3 line
  shift 3
  line=$("$softbake" bench "$scene" --frames "$frames" "$@" | tail -1)
  steps=$(field steps <<<"$line")
  printf '| %s | softbake %s | %s | %s | %s | %s | %s |\n' "$name" "$label" \
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
  default_steps=$steps
  # The peers are compared at the first setting that keeps the balls round (Jolt: 4 collision
  # steps of 5 iterations): for backward Euler that is one substep a frame, where nothing touches.
  [ "$name" = balls10k_falling_apart ] &&
    softbake_row "$scene" "$name" "implicit, 1 substep a frame" --integrator implicit --substeps 1
  softbake_row "$scene" "$name" explicit --integrator explicit
  softbake_row "$scene" "$name" xpbd --integrator xpbd
  line=$("$build/bench/bullet_peer_bench" "$scene" --steps "$default_steps" | tail -1)
  per_frame=$(divide "$default_steps" $((frames - 1)))
  printf '| %s | Bullet btSoftBody, 1 thread | %s | %s | %s | – | – |\n' "$name" "$per_frame" \
    "$(field steps_per_s <<<"$line")" "$(divide "$(field steps_per_s <<<"$line")" "$per_frame")"
  if [ -z "${SOFTBAKE_NO_BLENDER:-}" ]; then
    line=$(SOFTBAKE="$softbake" bash "$root/bench/blender_peer.sh" "$scene" --frames "$frames" 2>/dev/null | tail -1)
    printf '| %s | Blender 3.4 cloth, quality 5 | 5 | – | %s | – | – |\n' "$name" "$(field frames_per_s <<<"$line")"
  fi
done

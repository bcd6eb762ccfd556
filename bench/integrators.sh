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
#
# This VM's speed drifts by up to 1.5x over minutes, and a ratio of two runs minutes apart took
# that drift in. So softbake's implicit run and the peers run back to back, in rounds
# (SOFTBAKE_PEER_ROUNDS, default 3): each round gives its own ratios, listed after the table, and
# the table's rows are each side's median round.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
softbake=$build/cli/softbake
rounds=${SOFTBAKE_PEER_ROUNDS:-3}
field() { sed -n "s/.*\b$1=\([^ ]*\).*/\1/p"; }
divide() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
# The line of the median round by frames/s (the lower middle one for an even count).
median_line() { for line in "$@"; do printf '%s\t%s\n' "$(field frames_per_s <<<"$line")" "$line"; done |
  sort -g | sed -n "$(( ($# + 1) / 2 ))p" | cut -f2-; }
median() { printf '%s\n' "$@" | sort -g | sed -n "$(( ($# + 1) / 2 ))p"; }

softbake_row() {  # scene name, label, bench line
  local name=$1 label=$2 line=$3 steps
  steps=$(field steps <<<"$line")
  printf '| %s | softbake %s | %s | %s | %s | %s | %s | – | – |\n' "$name" "$label" \
    "$(divide "$steps" $((frames - 1)))" "$(field steps_per_s <<<"$line")" \
    "$(field frames_per_s <<<"$line")" "$(field solver_iterations_per_step <<<"$line")" \
    "$(field max_volume_error <<<"$line")"
}
softbake_bench() { "$softbake" bench "$scene" --frames "$frames" "$@" | tail -1; }

printf '| scene | integrator or peer | substeps/frame | steps/s | simulated frames/s | CG iterations/step | max abs(V/V_rest - 1) | max depth below the ground (m) | max intersecting pairs between bodies |\n'
printf '|---|---|---:|---:|---:|---:|---:|---:|---:|\n'
ratios=()
for scene in balls10k "$root/bench/scenes/balls10k_falling_apart.json" \
             "$root/examples/fig7_10k_faces.json"; do
  name=$(basename "$scene" .json)
  frames=$("$softbake" scene "$scene" | python3 -c 'import json,sys; print(json.load(sys.stdin)["settings"]["frames"])')
  frames=$((frames < 48 ? frames : 48))
  ours=() bullet=() blender=() by_bullet=() by_blender=()
  for ((round = 1; round <= rounds; ++round)); do
    ours+=("$(softbake_bench --integrator implicit)")
    bullet+=("$("$build/bench/bullet_peer_bench" "$scene" --frames "$frames" --substeps-per-frame 10 | tail -1)")
    blender_fps=–
    if [ -z "${SOFTBAKE_NO_BLENDER:-}" ]; then
      blender+=("$(SOFTBAKE="$softbake" bash "$root/bench/blender_peer.sh" "$scene" --frames "$frames" 2>/dev/null | tail -1)")
      blender_fps=$(field frames_per_s <<<"${blender[-1]}")
    fi
    ours_fps=$(field frames_per_s <<<"${ours[-1]}")
    bullet_fps=$(field frames_per_s <<<"${bullet[-1]}")
    by_bullet+=("$(divide "$ours_fps" "$bullet_fps")")
    by_blender+=("$([ "$blender_fps" = – ] && echo – || divide "$ours_fps" "$blender_fps")")
    ratios+=("$(printf '| %s | %d | %s | %s | %s | %s | %s |' "$name" "$round" "$ours_fps" \
      "$bullet_fps" "${by_bullet[-1]}" "$blender_fps" "${by_blender[-1]}")")
  done
  ratios+=("$(printf '| %s | median | | | **%s** | | **%s** |' "$name" "$(median "${by_bullet[@]}")" \
    "$(median "${by_blender[@]}")")")
  softbake_row "$name" implicit "$(median_line "${ours[@]}")"
  # The peers are compared at the first setting that keeps the balls round (Jolt: 4 collision
  # steps of 5 iterations): for backward Euler that is one substep a frame, where nothing touches.
  [ "$name" = balls10k_falling_apart ] &&
    softbake_row "$name" "implicit, 1 substep a frame" "$(softbake_bench --integrator implicit --substeps 1)"
  softbake_row "$name" explicit "$(softbake_bench --integrator explicit)"
  softbake_row "$name" xpbd "$(softbake_bench --integrator xpbd)"
  line=$(median_line "${bullet[@]}")
  printf '| %s | Bullet btSoftBody, 1 thread | 10 | %s | %s | – | %s | %s | %s |\n' "$name" \
    "$(field steps_per_s <<<"$line")" "$(field frames_per_s <<<"$line")" \
    "$(field max_volume_error <<<"$line")" "$(field max_penetration_m <<<"$line")" \
    "$(field max_pairs_between_bodies <<<"$line")"
  if [ -z "${SOFTBAKE_NO_BLENDER:-}" ]; then
    line=$(median_line "${blender[@]}")
    printf '| %s | Blender 3.4 cloth, quality 5 | 5 | – | %s | – | – | – | – |\n' "$name" "$(field frames_per_s <<<"$line")"
  fi
done
printf '\nRounds: softbake implicit (%s threads by default), Bullet and Blender back to back, simulated frames/s and ratios.\n\n' "$(nproc)"
printf '| scene | round | softbake implicit | Bullet, 10 substeps | × Bullet | Blender cloth, quality 5 | × Blender |\n'
printf '|---|---:|---:|---:|---:|---:|---:|\n'
printf '%s\n' "${ratios[@]}"

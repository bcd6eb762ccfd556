#!/usr/bin/env bash
# "auto" substeps of the implicit integrator on an imported mesh with small and sliver triangles
# beside a uniform mesh of about the same size and face count, in the same drop: the COLLADA duck
# (tests/data/meshes/duck.dae, 4 212 faces, its shortest edge a twentieth of the median, a finely
# modelled eye and beak) and a level-4 icosphere (5 120 faces) of the same extent, the upper one
# dropped 0.36 m onto the lower on the ground (bench/scenes/duck_pair.json, icosphere_pair.json).
# The integrator issue's target: the imported mesh within 2x of the uniform one's substeps. Each
# row also counts, by the tests' exact checker, the most intersecting triangle pairs between the
# two bodies at the end of a frame (contact_cases). What bench/results/integrators.md records.
#   bash bench/imported_substeps.sh [BUILD_DIR]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
field() { sed -n "s/.*\b$1=\([^ ]*\).*/\1/p"; }

printf '| scene | faces | substeps/frame | simulated frames/s | intersecting pairs between bodies, most in a frame |\n'
printf '|---|---:|---:|---:|---:|\n'
declare -A substeps
for name in duck_pair icosphere_pair; do
  scene=$root/bench/scenes/$name.json
  frames=48
  line=$("$build/cli/softbake" bench "$scene" --frames "$frames" | tail -1)
  substeps[$name]=$(awk -v s="$(field steps <<<"$line")" -v f=$((frames - 1)) 'BEGIN { printf "%.1f", s / f }')
  # contact_cases: | scene | integrator | bodies | faces | frames | between (frames) | ...
  between=$("$build/bench/contact_cases" "$scene" implicit | awk -F'|' '{ gsub(/^ +| +$/, "", $7); print $7 }')
  printf '| %s | %s | %s | %s | %s |\n' "$name" "$(field faces <<<"$line")" "${substeps[$name]}" \
    "$(field frames_per_s <<<"$line")" "$between"
done
awk -v a="${substeps[duck_pair]}" -v b="${substeps[icosphere_pair]}" \
  'BEGIN { printf "\nduck over icosphere, substeps: %.2f (target: at most 2)\n", a / b }'

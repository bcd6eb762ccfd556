#!/usr/bin/env bash
# The barriers of a step: every fork–join region the main thread opens with TBB (counted by
# bench/tbb_regions.cpp, loaded in front of libtbb) and every phase of the implicit solve's own
# region (core/dynamics/chunk_phases.hpp; `softbake bench` prints them as solver_phases_per_step).
# Each is a point where every thread waits for the slowest, so their count a step bounds what
# more cores can gain, on any machine (issue 35). Counts, not times: the machine's speed and load
# do not change them.
#   bash bench/regions_per_step.sh [BUILD_DIR] [SOFTBAKE] [THREADS] [SCENE:FRAMES ...]
# SOFTBAKE defaults to BUILD_DIR/cli/softbake: give another binary to count an older build.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
softbake=${2:-$build/cli/softbake}
threads=${3:-2}
shift $(($# < 3 ? $# : 3))
scenes=("$@")
((${#scenes[@]})) || scenes=(balls10k:12 "$root/examples/fig7_10k_faces.json:12")
shim=$build/bench/libsoftbake_tbb_regions.so
[[ -f $shim ]] || { echo "regions_per_step: $shim is missing; build target softbake_tbb_regions" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p"; }

echo "softbake bench SCENE --frames N -j $threads, $(basename "$softbake") of $(git -C "$root" rev-parse --short HEAD)"
echo
echo '| scene | steps | CG iterations/step | TBB regions/step | solve regions/step | solver phases/step | barriers/step |'
echo '|---|---:|---:|---:|---:|---:|---:|'
for entry in "${scenes[@]}"; do
  scene=${entry%:*} frames=${entry##*:}
  line=$(SOFTBAKE_TBB_REGIONS="$tmp/sites" LD_PRELOAD="$shim" \
    "$softbake" bench "$scene" --frames "$frames" -j "$threads" | grep '^scene=')
  steps=$(field steps <<<"$line")
  : >"$tmp/named"
  while read -r count who module offset; do
    [[ $who == main ]] || continue
    name=$(addr2line -f -C -e "$module" "$offset" | head -1)
    printf '%s\t%s\n' "$count" "${name%%(*}" >>"$tmp/named"
  done <"$tmp/sites"
  regions=$(awk -F'\t' '{ n += $1 } END { print n + 0 }' "$tmp/named")
  solves=$(awk -F'\t' '$2 ~ /ImplicitEuler::solve$/ { n += $1 } END { print n + 0 }' "$tmp/named")
  phases=$(field solver_phases_per_step <<<"$line")
  awk -v s="$(basename "${scene%.json}")" -v steps="$steps" -v it="$(field solver_iterations_per_step <<<"$line")" \
    -v r="$regions" -v v="$solves" -v p="$phases" 'BEGIN {
      # A solve region ends with its last phase: counted once.
      printf "| %s | %d | %s | %.1f | %.1f | %s | %.1f |\n", s, steps, it, r / steps, v / steps, p,
             (r - v) / steps + p }'
  # The call sites, summed by function, most first.
  awk -F'\t' -v steps="$steps" '{ n[$2] += $1 } END { for (f in n) printf "%.2f\t%s\n", n[f] / steps, f }' \
    "$tmp/named" | sort -rn >"$tmp/by_function"
  cp "$tmp/by_function" "$tmp/$(basename "${scene%.json}").sites"
done
echo
for sites in "$tmp"/*.sites; do
  echo "Regions a step by the function that opens them, $(basename "${sites%.sites}"):"
  echo
  awk -F'\t' '{ printf "    %6s  %s\n", $1, $2 }' "$sites"
  echo
done

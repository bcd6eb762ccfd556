#!/usr/bin/env bash
# Contacts kept apart inside the implicit step against contacts answered after it, and Bullet at
# its own 10 substeps a frame, on the same scenes in one run: what bench/results/integrators.md
# records for collisions.contactsInStep.
#   bash bench/contacts_in_step.sh [BUILD_DIR]
# Scenes, 48 frames at "auto" substeps: balls10k (the two-layer pile), figure 7 and the eight balls
# falling apart; then the pile and figure 7 at fixed 1 and 2 substeps a frame, contacts in the step.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene() {  # name, source scene (file or built-in), substeps ("auto" or a count)
  "$build/cli/softbake" scene "$2" | python3 -c '
import json, sys
s = json.load(sys.stdin)
s["settings"]["frames"] = min(48, s["settings"].get("frames", 48))
s["settings"]["substeps"] = sys.argv[1] if sys.argv[1] == "auto" else int(sys.argv[1])
json.dump(s, open(sys.argv[2], "w"))' "$3" "$work/$1.json"
  echo "$work/$1.json"
}
"$build/bench/contact_cases" --header
for source in balls10k "$root/examples/fig7_10k_faces.json" "$root/bench/scenes/balls10k_falling_apart.json"; do
  file=$(scene "$(basename "$source" .json)" "$source" auto)
  for mode in afterstep instep; do
    "$build/bench/contact_cases" "$file" implicit set_aside failsafe "$mode"
  done
done
for source in balls10k "$root/examples/fig7_10k_faces.json"; do
  for substeps in 1 2; do
    file=$(scene "$(basename "$source" .json)_$substeps" "$source" "$substeps")
    "$build/bench/contact_cases" "$file" implicit set_aside failsafe instep
  done
done
for source in balls10k "$root/examples/fig7_10k_faces.json" "$root/bench/scenes/balls10k_falling_apart.json"; do
  "$build/bench/bullet_peer_bench" "$source" --frames 48 --substeps-per-frame 10 | tail -1
done

#!/usr/bin/env bash
# The hard contact cases and figure 7, frame by frame under the default (implicit) integrator, the
# paper's explicit Euler, and the implicit one without the failsafe stage (the paper's pipeline
# alone): the table bench/results/contacts.md records.
#   bash bench/contacts.sh [BUILD_DIR] > bench/results/contacts.txt
# Scenes, all in examples/: a pinned sheet with a ball, a mixed pile of eight bodies, a heavy ball
# on a jelly one, two parts that start inside each other, a flag folding onto the ground, and
# figure 7. Intersecting pairs come from the tests' exact checker
# (tests/support/intersection_checker.hpp), counted at the end of every frame; its time is not in
# frames/s.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
cases=$build/bench/contact_cases  # and contact_sweep beside it
[ -x "$cases" ] || { echo "contacts.sh: build $cases first (it needs the test suite)" >&2; exit 1; }

"$cases" --header
# Per frame, the implicit runs with and without the failsafe, for the chart.
frames=$root/bench/results/contacts_frames.csv
rm -f "$frames"
for name in sheet_ball mixed_pile heavy_on_jelly glued_assembly flag_fold fig7_10k_faces; do
  scene=$root/examples/$name.json
  "$cases" "$scene" implicit separate failsafe "--csv=$frames"
  "$cases" "$scene" explicit
  "$cases" "$scene" implicit separate nofailsafe "--csv=$frames"
done
python3 "$root/bench/plot_bench.py" contacts "$frames" "$root/bench/results/contacts.svg" >&2
"$cases" "$root/examples/glued_assembly.json" implicit ignore |
  sed 's/^| glued_assembly /| glued_assembly (ignore) /'
# 64 balls of every preset at 1:10 onto a static sphere (bench/scenes/make_pile64.py).
"$cases" "$root/bench/scenes/pile64.json" implicit
# Two balls of every pair of presets dropped from 5 m at mass ratios (upper:lower) from 1:100 to
# 100:1: the most intersecting pairs between them at a frame's end and the most energy above the
# start, or the frame the run blew up at.
echo
"$build/bench/contact_sweep"

#!/usr/bin/env bash
# Multi-part files of assimp's test corpus whose parts overlap as modelled, baked for 48 frames as
# `softbake run FILE` bakes them (auto substeps, the default material, dropped onto a ground), with
# the tests' exact checker at every frame's end (bench/contact_cases). Issue 34's target: every
# pair that intersects at the start is set aside or separated, and no new pair appears. A row
# gives the most intersecting pairs of a frame that did not intersect at the start ("new pairs":
# pairs of overlaps that slid), and of those the ones between surfaces, or within one, that had no
# intersecting pair at all at the start ("where none overlapped": a crossing where nothing did),
# and of those the ones whose triangles stood apart at the start by more than the rounding of their
# coordinates (faces modelled onto each other start a float step apart, to either side).
#   bash bench/new_pairs.sh CORPUS_DIR [BUILD_DIR] [FRAMES]
# CORPUS_DIR is assimp's test/models (`fetch` assimp/assimp); it is read, never copied here.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
corpus=${1:?usage: bench/new_pairs.sh CORPUS_DIR [BUILD_DIR] [FRAMES]}
build=${2:-$root/build}
frames=${3:-48}
files=(
  MS3D/jeep1.ms3d
  OBJ/regr01.obj
  FBX/spider.fbx
  ASE/MotionCaptureROM.ase
  Collada/teapots.DAE
  BLEND/HUMAN.blend
  LWO/LWO2/UglyVertexColors.lwo
  NFF/cone.nff
)
echo "contact_cases FILE implicit set_aside failsafe instep --frames=$frames, $(nproc) cores, $(git -C "$root" rev-parse --short HEAD)"
echo
"$build/bench/contact_cases" --header | sed '1s/^| scene |/| file |/'
for file in "${files[@]}"; do
  row=$("$build/bench/contact_cases" "$corpus/$file" implicit set_aside failsafe instep \
    "--frames=$frames" 2>&1 | tail -1) || row="| $(basename "$file") | failed: $row |"
  echo "${row/| $(basename "${file%.*}") |/| $file |}"
done

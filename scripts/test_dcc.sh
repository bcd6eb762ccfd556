#!/usr/bin/env bash
# The Blender add-on, end to end and headless (issue 16):
#
#   1. installs Debian's `blender` when it is missing (apt-get; sudo when not root);
#   2. bakes the built-in default scene (240 frames) with --pc2 --vdb --up z into a temporary
#      folder, with the softbake built in SOFTBAKE_BUILD_DIR (default: build);
#   3. builds the add-on zip (dcc/blender/make_addon_zip.py);
#   4. runs Blender headless on dcc/blender/check_import.py, which installs and enables the
#      add-on, imports the manifest and checks every body's evaluated mesh at frames 1, 60 and 240
#      against the OBJ sequence (within 1e-5, Y-up turned to Blender's Z-up), the VDB volume
#      object, the frame range and fps, and that broken bakes are refused naming the file;
#   5. bakes `balls100k` (20 bodies, 102 400 faces) for a few frames and times the import.
#
# Usage: scripts/test_dcc.sh            (from anywhere; exit 0 when every check passes)
# Environment: SOFTBAKE_BUILD_DIR (default build), BLENDER (default blender),
#              SOFTBAKE_DCC_KEEP=1 keeps the temporary folder, BALLS100K_FRAMES (default 3).
# The add-on is installed into a temporary Blender user folder (BLENDER_USER_SCRIPTS and
# BLENDER_USER_CONFIG), never into ~/.config/blender.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${SOFTBAKE_BUILD_DIR:-build}
[[ $build = /* ]] || build=$root/$build
softbake=$build/cli/softbake
blender=${BLENDER:-blender}
frames_100k=${BALLS100K_FRAMES:-3}
started=$SECONDS

step() { printf '\n== %s (%ds)\n' "$*" $((SECONDS - started)); }

if [[ ! -x $softbake ]]; then
  echo "test_dcc: no softbake at $softbake; build it first (cmake --build ${build#"$root"/})" >&2
  exit 2
fi

if ! command -v "$blender" >/dev/null 2>&1; then
  step "installing Debian's blender"
  sudo=()
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null 2>&1 || { echo "test_dcc: blender is missing and there is no sudo to install it" >&2; exit 2; }
    sudo=(sudo)
  fi
  # Debian's blender has no Recommends that headless use needs.
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends blender
fi
"$blender" --version 2>/dev/null | head -n 1

tmp=$(mktemp -d "${TMPDIR:-/tmp}/softbake_dcc.XXXXXX")
if [[ ${SOFTBAKE_DCC_KEEP:-0} = 1 ]]; then
  echo "test_dcc: keeping $tmp"
else
  trap 'rm -rf "$tmp"' EXIT
fi
export BLENDER_USER_SCRIPTS=$tmp/blender_user/scripts BLENDER_USER_CONFIG=$tmp/blender_user/config

run_blender() {  # the check script's arguments
  "$blender" -b --factory-startup --python-exit-code 1 \
    --python "$root/dcc/blender/check_import.py" -- "$@"
}

bake() {  # softbake run ARGS, quiet; its output is shown when it fails
  local log=$tmp/bake.log bake_started=$SECONDS
  if ! "$softbake" run "$@" --quiet >"$log" 2>&1; then
    cat "$log" >&2
    echo "test_dcc: softbake run $* failed" >&2
    exit 1
  fi
  tail -n 2 "$log"
  echo "baked in $((SECONDS - bake_started)) s"
}

step "baking the default scene (240 frames, --pc2 --vdb --up z, no PNG)"
bake -o "$tmp/default" --pc2 --vdb --up z --no-render

step "building the add-on zip"
python3 "$root/dcc/blender/make_addon_zip.py" "$tmp/softbake_blender.zip"

step "importing the default scene in Blender and checking frames 1, 60, 240"
run_blender --addon-zip "$tmp/softbake_blender.zip" --manifest "$tmp/default/manifest.json" \
  --frames 1,60,240 --tolerance 1e-5 --check-errors 2>&1 | tee "$tmp/check_default.log"
grep -q '^PASS' "$tmp/check_default.log"

step "baking balls100k ($frames_100k frames, --pc2 --up z, no PNG)"
bake balls100k -o "$tmp/balls100k" --frames "$frames_100k" --pc2 --no-render --up z

step "timing the import of 102 400 faces"
run_blender --manifest "$tmp/balls100k/manifest.json" --timing-only --addon-zip \
  "$tmp/softbake_blender.zip" 2>&1 | tee "$tmp/check_100k.log"
grep -q '^PASS' "$tmp/check_100k.log"

echo
grep -h '^IMPORT TIME' "$tmp/check_default.log" "$tmp/check_100k.log"
echo "PASS: scripts/test_dcc.sh in $((SECONDS - started)) s"

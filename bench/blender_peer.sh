#!/usr/bin/env bash
# The Blender cloth peer benchmark on a softbake scene:
#
#   bench/blender_peer.sh SCENE [--frames N] [--quality Q]
#
# SCENE is anything `softbake scene` takes (a built-in name such as balls10k, or a scene .json).
# Installs Debian's blender when it is missing, resolves SCENE to plain JSON with
# `softbake scene` (the binary is $SOFTBAKE, default build/cli/softbake), runs
# bench/blender_cloth_peer.py on it in background Blender and prints its one result line:
#
#   peer=blender_cloth scene=balls10k faces=10240 frames=24 seconds=... frames_per_s=... ...
#
# Blender's own output is dropped unless the run fails; the per-body report goes to stderr.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
softbake="${SOFTBAKE:-$root/build/cli/softbake}"

if [[ $# -lt 1 ]]; then
  echo "usage: $0 SCENE [--frames N] [--quality Q]" >&2
  exit 2
fi
scene="$1"
shift

install_blender() {
  local sudo=()
  [[ $(id -u) -eq 0 ]] || sudo=(sudo)
  echo "blender_peer.sh: installing blender with apt-get" >&2
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q >&2
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends blender >&2
}
command -v blender > /dev/null || install_blender

if [[ ! -x "$softbake" ]]; then
  echo "blender_peer.sh: $softbake not found; build softbake or set SOFTBAKE" >&2
  exit 2
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$softbake" scene "$scene" > "$work/scene.json"

# Mesh paths in a scene file are relative to its folder, not to the temporary copy.
base_dir="$root"
[[ -f "$scene" ]] && base_dir="$(cd "$(dirname "$scene")" && pwd)"

status=0
blender -b --factory-startup --python "$root/bench/blender_cloth_peer.py" -- \
  "$work/scene.json" --base-dir "$base_dir" "$@" > "$work/blender.log" || status=$?
if ! grep '^peer=blender_cloth ' "$work/blender.log"; then
  cat "$work/blender.log" >&2
  echo "blender_peer.sh: the Blender run printed no result (status $status)" >&2
  exit $(( status == 0 ? 1 : status ))
fi
exit "$status"

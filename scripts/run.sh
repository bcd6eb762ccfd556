#!/usr/bin/env bash
# Sets up and builds softbake if needed, then runs `softbake run` from the caller's folder (by
# default the built-in scene, into ./out). Arguments are passed on:
#   bash scripts/run.sh examples/fig5_ground.json --out out/fig5
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh" >/dev/null
args=("$@")
has_out=0
for arg in "$@"; do
  case "$arg" in -o | --out | --out=*) has_out=1 ;; esac
done
((has_out)) || args+=(--out out)
build=${SOFTBAKE_BUILD_DIR:-build}
[[ $build = /* ]] || build=$root/$build
exec "$build/cli/softbake" run "${args[@]}"

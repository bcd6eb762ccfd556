#!/usr/bin/env bash
# Renders tests/golden/ again with the current build, the same runs tests/cli/cli_test.cpp makes:
# use it when a change to what the frames show is meant, and look at every frame before committing.
#   SOFTBAKE_BUILD_DIR  build folder (default: build)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
softbake=${SOFTBAKE_BUILD_DIR:-build}/cli/softbake
[ -x "$softbake" ] || { echo "regenerate_golden: build softbake first ($softbake)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The built-in scene and figure 5, 120 frames at 320x240 (RenderedFramesMatchTheGoldenFrames).
"$softbake" run --render --size 320x240 --frames 120 -q -o "$work/default" >/dev/null
"$softbake" run examples/fig5_ground.json --render --size 320x240 --frames 120 -q -o "$work/fig5" >/dev/null
for frame in 0001 0010 0060 0120; do cp "$work/default/png/default_$frame.png" tests/golden/; done
for frame in 0001 0060 0120; do cp "$work/fig5/png/fig5_ground_$frame.png" tests/golden/; done

# The hard contact cases, each at the frame its run ends on (ContactExampleFrame).
for case in sheet_ball:48 mixed_pile:48 heavy_on_jelly:36 glued_assembly:24 flag_fold:48; do
  name=${case%%:*} frame=${case##*:}
  "$softbake" run "examples/$name.json" --render --size 320x240 --frames "$frame" -q \
    -o "$work/$name" >/dev/null
  cp "$work/$name/png/$(printf '%s_%04d.png' "$name" "$frame")" tests/golden/
done
echo "regenerate_golden: wrote $(ls tests/golden/*.png | wc -l) frames to tests/golden/; review them with git diff --stat and an image viewer"

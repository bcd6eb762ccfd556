#!/usr/bin/env bash
# The measurements behind `softbake compare`'s default thresholds (docs/regression.md): frame 1 of
# the built-in scene at 320x240, the camera fixed 1.6 m in front of the first ball (1 m across, so
# it spans about 200 pixels and 1% of its size is 2 pixels), rendered again with one thing
# changed; each variant compared with its reference by every metric. Prints a Markdown table.
#   SOFTBAKE_BUILD_DIR  build folder (default: build)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
softbake=$PWD/${SOFTBAKE_BUILD_DIR:-build}/cli/softbake
[ -x "$softbake" ] || { echo "metric_study: build softbake first ($softbake)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# name, then Python statements on the scene `s` (the variant's change).
variants=(
  "reference|"
  "samples1|s['render']['samples'] = 1"
  "samples8|s['render']['samples'] = 8"
  "camera_half_pixel|shift(0.5)"
  "camera_1_pixel|shift(1)"
  "camera_2_pixels|shift(2)"
  "body_0.25%|move(0.0025)"
  "body_0.5%|move(0.005)"
  "body_1%|move(0.01)"
  "body_2%|move(0.02)"
  "body_1%_nearer|s['bodies'][0]['transform']['translate'][2] += 0.01"
  "colour|s['bodies'][0]['color'] = [0.3, 0.5, 0.8]"
  "colour_2%_darker|s['bodies'][0]['color'] = [0.3, 0.5, 0.784]"
  "colour_5%_darker|s['bodies'][0]['color'] = [0.3, 0.5, 0.76]"
  "colour_10%_darker|s['bodies'][0]['color'] = [0.3, 0.5, 0.72]"
)
for variant in "${variants[@]}"; do
  name=${variant%%|*} change=${variant#*|}
  python3 - "$work/$name.json" "$change" <<'PY'
import json, math, sys
s = json.load(open("examples/default.json"))
s["settings"]["frames"] = 1
s["render"] = {"camera": {"position": [-1.2, 1.6, 1.6], "target": [-1.2, 1.5, 0.0]}}
pixel = 2 * 1.6 * math.tan(math.radians(20)) / 240  # metres per pixel at the target
def shift(pixels):
    for key in ("position", "target"):
        s["render"]["camera"][key][0] += pixels * pixel
def move(metres):
    s["bodies"][0]["transform"]["translate"][0] += metres
exec(sys.argv[2])
json.dump(s, open(sys.argv[1], "w"))
PY
  "$softbake" run "$work/$name.json" --size 320x240 --render --no-cache -q -o "$work/$name" >/dev/null
done

numbers() {  # the part of compare's line after the metric's name, without the PSNR
  "$softbake" compare "$@" | head -1 | sed -E 's/^[^:]*: [^:]*: [a-z]+: //; s/; (PSNR [0-9.]+ dB|identical)$//'
}
echo "| variant | reference | flip, edges may move 1 pixel (default) | flip, pixel against pixel | pixel, edges may move 1 pixel | yee |"
echo "| --- | --- | --- | --- | --- | --- |"
for variant in "${variants[@]}"; do
  name=${variant%%|*}
  [ "$name" = reference ] || [ "$name" = colour ] && continue
  reference=reference
  case $name in colour_*) reference=colour ;; esac
  a=$work/$reference/png/default_0001.png b=$work/$name/png/default_0001.png
  echo "| $name | $reference | $(numbers "$a" "$b") | $(numbers "$a" "$b" --align 0) |" \
       "$(numbers "$a" "$b" --metric pixel) | $(numbers "$a" "$b" --metric yee) |"
done

#!/usr/bin/env bash
# Renders docs/figures/ again with the current build: softbake's frames for the figures of Mesit &
# Guha that draw contacts (4, 5a/5b, 6) and the built-in scene, as the README shows them. Run it
# when a change to the simulator or the renderer changes what they show, and look at every frame
# before committing.
#   SOFTBAKE_BUILD_DIR  build folder (default: build)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
softbake=${SOFTBAKE_BUILD_DIR:-build}/cli/softbake
[ -x "$softbake" ] || { echo "render_paper_figures: build softbake first ($softbake)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p docs/figures
size=640x360

# render NAME FRAME OUTPUT [RUN OPTIONS...]: runs the scene up to FRAME and keeps that frame.
render() {
  local scene=$1 frame=$2 output=$3
  shift 3
  "$softbake" run ${scene:+"$scene"} --render --size "$size" --frames "$frame" -q \
    -o "$work/$output" "$@" >/dev/null
  cp "$(ls "$work/$output"/png/*_"$(printf '%04d' "$frame")".png)" "docs/figures/$output.png"
}

# The built-in scene as the balls meet.
render "" 12 default_frame12
# Figure 4: the jelly ball pressed into the rubber ball, 125 contacts between them, seen through
# the translucent bodies (the contact view, automatic for two bodies).
render examples/fig4_two_bodies.json 13 fig4_frame13
# Figure 4 again, each contact in its kind's colour: edge-triangle red, particle-triangle orange,
# corner magenta, plane blue.
kinds=$work/fig4_kinds.json
sed 's/"output": { "contacts": true }/"output": { "contacts": true },\n  "render": { "contact_color": "kind" }/' \
  examples/fig4_two_bodies.json >"$kinds"
grep -q '"contact_color": "kind"' "$kinds" ||
  { echo "render_paper_figures: could not add render.contact_color to fig4_two_bodies.json" >&2; exit 1; }
render "$kinds" 13 fig4_kinds_frame13
# Figure 5: the ball on the ground with the response (5a), and falling through it without (5b).
# Its contacts are plane contacts, under the ball: one body keeps solid bodies by default, so the
# contact view is asked for.
render examples/fig5_ground.json 16 fig5a_frame16 --contacts-view xray
render examples/fig5_ground.json 16 fig5b_frame16 --contacts-view xray --response none
# Figure 6: soft bodies falling onto a static sphere, as they land on it.
render examples/fig6_falling_on_sphere.json 18 fig6_frame18

echo "render_paper_figures: wrote $(ls docs/figures/*.png | wc -l) frames to docs/figures/; look at each before committing"

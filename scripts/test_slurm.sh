#!/usr/bin/env bash
# The farm for real: a one-node Slurm cluster on this machine (scripts/slurm_local.sh), a wedge of
# 3 variants x 96 frames baked by `softbake farm slurm` in chunks of 16 with 1, 2 and 4 task slots.
# Asserts that every output is there exactly once (`softbake verify`) and byte-identical to a
# single-machine `softbake run` of the same variant, and prints the farm's wall time per slot count.
# Needs root (the daemons), a built softbake (scripts/setup.sh) and Debian's archive for slurm-wlm.
#   SOFTBAKE_BUILD_DIR  build folder (default: build)
#   SLURM_TEST_SLOTS    slot counts to time (default: "1 2 4")
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
repo=$PWD
softbake=$repo/${SOFTBAKE_BUILD_DIR:-build}/cli/softbake
[ -x "$softbake" ] || { echo "test_slurm: build softbake first ($softbake)" >&2; exit 1; }
bash scripts/slurm_local.sh install

work=$(mktemp -d /tmp/softbake-slurm-XXXXXX)
cluster=""
cleanup() {
  [ -n "$cluster" ] && bash "$repo/scripts/slurm_local.sh" stop "$cluster" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

# Two balls of figure 4, their contacts, PNG frames: every output the cache feeds but VDB (which
# `export` writes the same way and the resume tests compare).
cat >"$work/scene.json" <<'JSON'
{
  "name": "farm",
  "settings": { "fps": 24, "frames": 96 },
  "bodies": [
    { "name": "lower", "mesh": { "primitive": "icosphere", "subdivisions": 3, "radius": 0.6 },
      "transform": { "translate": [0, 0.65, 0] }, "material": "rubber" },
    { "name": "upper", "mesh": { "primitive": "icosphere", "subdivisions": 3, "radius": 0.5 },
      "transform": { "translate": [0.03, 1.9, 0.0] }, "material": "jelly", "mass": 0.5,
      "velocity": [0, -2, 0] }
  ],
  "colliders": [ { "type": "plane", "name": "ground" } ],
  "output": { "contacts": true }
}
JSON
vary=(--vary 'bodies[1].velocity=[0,-1,0],[0,-2,0],[0,-3,0]')
run_options=(--render --size 320x180)

# The reference: each variant baked on this machine by one `softbake run`.
"$softbake" wedge "$work/scene.json" "${vary[@]}" -o "$work/reference" --no-bake >/dev/null
for variant in "$work"/reference/wedge_*/; do
  "$softbake" run "$variant/scene.json" -o "$variant" -q "${run_options[@]}" >/dev/null
done

# Files a variant's folder must hold, by content; the manifest records how it was made, and the
# wedge's own files are not outputs.
digest() { (cd "$1" && find . -type f ! -name manifest.json ! -name scene.json ! -name run.log |
  LC_ALL=C sort | xargs sha256sum); }

results=()
for slots in ${SLURM_TEST_SLOTS:-1 2 4}; do
  cluster=$work/cluster_$slots
  exports=$(bash scripts/slurm_local.sh start "$cluster" --slots "$slots")
  eval "$exports"
  out=$work/farm_$slots
  start=$(date +%s%N)
  "$softbake" farm slurm "$work/scene.json" "${vary[@]}" -o "$out" --chunk 16 --submit -- \
    "${run_options[@]}" >"$work/submit_$slots.txt"
  verify=$(sed -n 's/^verify: //p' "$work/submit_$slots.txt")
  # Until the last job, the check, has left the queue.
  for _ in $(seq 1200); do
    [ -z "$(squeue -h -j "$verify" 2>/dev/null)" ] && break
    sleep 0.5
  done
  milliseconds=$((($(date +%s%N) - start) / 1000000))
  state=$(scontrol show job "$verify" | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  if [ "$state" != COMPLETED ]; then
    echo "test_slurm: the verify job ended $state with $slots slots; logs:" >&2
    tail -n 20 "$out"/slurm/logs/* >&2
    exit 1
  fi
  for variant in "$work"/reference/wedge_*/; do
    name=$(basename "$variant")
    if ! diff <(digest "$variant") <(digest "$out/$name") >"$work/diff.txt"; then
      echo "test_slurm: $name from the farm ($slots slots) differs from a single run:" >&2
      head "$work/diff.txt" >&2
      exit 1
    fi
  done
  files=$(digest "$out/wedge_000" | wc -l)
  bash scripts/slurm_local.sh stop "$cluster" >/dev/null
  cluster=""
  results+=("$(printf '%d slots: %4d.%01d s' "$slots" $((milliseconds / 1000)) $((milliseconds % 1000 / 100)))")
done
echo "test_slurm: 3 variants x 96 frames, chunks of 16: every output once, byte-identical to single" \
  "runs ($files files a variant). Farm wall time, submit to the check's end:"
printf '  %s\n' "${results[@]}"

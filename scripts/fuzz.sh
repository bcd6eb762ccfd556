#!/usr/bin/env bash
# Runs every libFuzzer target (fuzz/) for SECONDS each (default 60), after installing clang and
# libFuzzer if missing and configuring and building the fuzz tree (clang, ASan, UBSan) if needed.
# Exits non-zero when a target finds anything (a crash, a sanitizer report, a broken promise of
# fuzz_entries.hpp, a timeout or running out of memory); the input that did it is left in
# FINDINGS/<target>/, to be fixed and committed under tests/data/fuzz/<target>/.
#
#   bash scripts/fuzz.sh [SECONDS]
#   SOFTBAKE_FUZZ_BUILD_DIR  build folder (default: build-fuzz); its corpus/<target> keeps what
#                            each run learnt, so the next run starts from there
#   SOFTBAKE_FUZZ_FINDINGS   where crash inputs go (default: BUILD/findings)
#   SOFTBAKE_FUZZ_TARGETS    which targets (default: scene ply_guard mesh_import)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

seconds=${1:-60}
[[ $seconds =~ ^[1-9][0-9]*$ ]] || { echo "usage: scripts/fuzz.sh [SECONDS]" >&2; exit 2; }
build=${SOFTBAKE_FUZZ_BUILD_DIR:-build-fuzz}
findings=${SOFTBAKE_FUZZ_FINDINGS:-$build/findings}
read -r -a targets <<<"${SOFTBAKE_FUZZ_TARGETS:-scene ply_guard mesh_import}"

bash scripts/setup.sh --fuzz-tools --packages-only
if [ ! -f "$build/CMakeCache.txt" ]; then
  echo "fuzz: configuring $build (clang, libFuzzer, ASan, UBSan)" >&2
  # Optimised with line numbers: fast enough to fuzz, and a finding's stack names the line.
  CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSOFTBAKE_FUZZ=ON -DSOFTBAKE_WERROR=ON -DSOFTBAKE_BUILD_TESTS=OFF \
    -DSOFTBAKE_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target "${targets[@]/%/_fuzzer}"

# The seeds: the examples and the test meshes, fresh each run. A mesh seed is the file behind
# one byte naming its format (fuzz_entries.hpp: .obj .ply .stl .gltf .glb .fbx are 0 to 5).
# Companion files (AnimatedMorphSphere's .bin) are left out, since the target reads only the one
# buffer, and so are meshes over 16 KiB but the one binary FBX: a big seed makes every execution
# that mutates it slow (an 88 KiB OBJ takes 0.15 s a run), and small ones reach the same code.
format_byte() {
  case "${1,,}" in
    *.obj) echo 0 ;; *.ply) echo 1 ;; *.stl) echo 2 ;; *.gltf) echo 3 ;; *.glb) echo 4 ;;
    *.fbx) echo 5 ;; *) echo "" ;;
  esac
}
seeds=$build/seeds
rm -rf "$seeds"
mkdir -p "$seeds/scene" "$seeds/ply_guard" "$seeds/mesh_import"
cp examples/*.json "$seeds/scene/"
# The assimp-crashing PLY of tests/data/meshes/broken is a seed on purpose: the PLY guard must
# refuse it before assimp sees it, in both targets.
cp fuzz/seeds/ply/*.ply tests/data/meshes/*.ply tests/data/meshes/broken/*.ply "$seeds/ply_guard/"
for file in fuzz/seeds/meshes/* fuzz/seeds/ply/* tests/data/meshes/* tests/data/meshes/broken/* \
  tests/data/import/box.gltf tests/data/import/box.glb; do
  byte=$(format_byte "$file")
  [ -n "$byte" ] && [ -f "$file" ] || continue
  [ "$(stat -c %s "$file")" -le 16384 ] || [[ ${file,,} == *.fbx ]] || continue
  { printf "\\x$(printf %02x "$byte")"; cat "$file"; } >"$seeds/mesh_import/$(basename "$file")"
done

# Leaks inside assimp only; see the file.
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
failed=()
summary=()
for target in "${targets[@]}"; do
  corpus=$build/corpus/$target
  mkdir -p "$corpus" "$findings/$target"
  log=$build/fuzz-$target.log
  options=(-max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -max_len=131072
           -print_final_stats=1 -artifact_prefix="$findings/$target/")
  [ -f "fuzz/$target.dict" ] && options+=(-dict="fuzz/$target.dict")
  echo "fuzz: $target for ${seconds} s" >&2
  status=0
  "$build/fuzz/${target}_fuzzer" "${options[@]}" "$corpus" "$seeds/$target" >"$log" 2>&1 ||
    status=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  summary+=("$target: ${runs:-?} executions in ${seconds} s, corpus $(find "$corpus" -type f | wc -l) inputs")
  if [ "$status" -ne 0 ]; then
    failed+=("$target")
    echo "fuzz: $target FOUND something (exit $status); the input is in $findings/$target/:" >&2
    grep -E "^(==[0-9]+==|SUMMARY|artifact_prefix|Test unit written)|FuzzFinding|terminate" "$log" \
      >&2 || tail -40 "$log" >&2
  fi
done
printf 'fuzz: %s\n' "${summary[@]}"
if ((${#failed[@]})); then
  echo "fuzz: findings in ${failed[*]} (logs: $build/fuzz-<target>.log)" >&2
  exit 1
fi
echo "fuzz: nothing found"

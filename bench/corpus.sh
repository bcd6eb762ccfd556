#!/usr/bin/env bash
# assimp's own test corpus as a robustness benchmark: every model file in it baked for 2 frames,
# one softbake run per file, each outcome classified and timed. What bench/results/corpus.md
# records (issue 34).
#
#   bash bench/corpus.sh CORPUS_DIR [OUT_TABLE]
#
# CORPUS_DIR is `test/models` of assimp/assimp (a checkout, or `git archive HEAD test/models` of
# one, unpacked); it is never copied into this repository. OUT_TABLE defaults to
# bench/results/corpus.md. Each file runs as
#   timeout -k KILL_AFTER LIMIT softbake run FILE --frames 2 --no-render -j 1 -o TMP
# under `ulimit -v` (see CORPUS_MEM_MIB), one file at a time, in sorted order, except the files of
# CORPUS_LAST, which run after all the others. The output folders live in a temporary folder that
# is removed at the end.
#
# Which files are models, decided by the name alone (case-insensitive): every file except
#   images and textures: .png .jpg .jpeg .gif .bmp .tga .dds .tif .tiff .psd .pcx .hdr .exr .ktx
#     .ktx2 .webp .basis
#   companions of a model: .mtl (OBJ materials), .bin (glTF buffers), .material (Ogre materials),
#     .glsl .vert .frag (shaders)
#   text: .txt .md, and files named readme* or licen[cs]e* / copying*
# Files without an extension stay in: the corpus keeps its format-detection cases that way.
#
# Outcomes, in this order of precedence:
#   timed out  timeout's status 124, or 137 at or past the limit (the kill after -k)
#   baked      exit 0
#   blew up    the message says the simulation blew up
#   crashed    killed by a signal other than the time limit's, or "assimp crashed reading the file"
#   refused    exit 1 or 2 with a message on stderr (its first line is kept)
#   other      anything else
# Recorded per file: wall seconds; bodies and faces (triangles), from manifest.json where the run
# wrote one, else from the "scene '...': N bodies, ..., N triangles" line; substeps per frame (the
# steps the run took for its one simulated frame, else the "substeps: N per frame" it announced);
# the triangle pairs of "warning: surfaces intersect at the start" summed over all surface pairs.
#
# Settings, from the environment:
#   SOFTBAKE          the binary (default build/cli/softbake under the repository root)
#   CORPUS_TIMEOUT    seconds per file (default 60)
#   CORPUS_KILL_AFTER seconds after the limit's SIGTERM before SIGKILL (default 10)
#   CORPUS_MEM_MIB    `ulimit -v` per run, in MiB (default 8192; 0 for none). IQM/invalid/
#                     InvalidMeshOffset.iqm makes assimp 5.2.5 take all of a machine's memory; the
#                     limit keeps the machine usable (assimp reads in a child process, which
#                     inherits it)
#   CORPUS_LAST       paths under CORPUS_DIR run last, alone, space-separated (default
#                     "IQM/invalid/InvalidMeshOffset.iqm")
#   CORPUS_JOBS       files run at once (default 1); more skews the timings
#   CORPUS_FILTER     an extended regular expression: only paths that match it run (default all)
# Needs bash 5, GNU coreutils' timeout, jq.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//' >&2; exit "$1"; }
if [ $# -lt 1 ] || [ $# -gt 2 ]; then usage 2; fi
if [ "$1" = -h ] || [ "$1" = --help ]; then usage 0; fi
script=${BASH_SOURCE[0]} args=("$@")
corpus=$(cd "$1" && pwd)
table=${2:-$root/bench/results/corpus.md}
softbake=${SOFTBAKE:-$root/build/cli/softbake}
limit=${CORPUS_TIMEOUT:-60}
kill_after=${CORPUS_KILL_AFTER:-10}
mem_mib=${CORPUS_MEM_MIB:-8192}
last=${CORPUS_LAST-IQM/invalid/InvalidMeshOffset.iqm}
jobs=${CORPUS_JOBS:-1}
filter=${CORPUS_FILTER:-}
frames=2
[ -x "$softbake" ] || { echo "corpus.sh: no softbake at $softbake (build it, or set SOFTBAKE)" >&2; exit 1; }
command -v jq >/dev/null || { echo "corpus.sh: needs jq" >&2; exit 1; }
softbake=$(cd "$(dirname "$softbake")" && pwd)/$(basename "$softbake")

tmp=$(mktemp -d "${TMPDIR:-/tmp}/softbake-corpus.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# --- the files --------------------------------------------------------------------------------
skip_ext='png|jpe?g|gif|bmp|tga|dds|tiff?|psd|pcx|hdr|exr|ktx2?|webp|basis|mtl|bin|material|glsl|vert|frag|txt|md'
skip_name='(readme|licen[cs]e|copying)[^/]*'
mapfile -t files < <(cd "$corpus" && find . -type f -printf '%P\n' |
  grep -Eiv "\.($skip_ext)\$" | grep -Eiv "(^|/)$skip_name\$" |
  { if [ -n "$filter" ]; then grep -E "$filter" || true; else cat; fi } | LC_ALL=C sort)
[ ${#files[@]} -gt 0 ] || { echo "corpus.sh: no model files under $corpus" >&2; exit 1; }
# A CORPUS_LAST entry names a path under CORPUS_DIR or the end of one (CORPUS_DIR may be above
# test/models).
declare -A is_last=()
ordered=() tail_files=()
for f in "${files[@]}"; do
  for l in $last; do
    if [ "$f" = "$l" ] || [[ "$f" == */"$l" ]]; then is_last[$f]=1; fi
  done
  if [ -n "${is_last[$f]:-}" ]; then tail_files+=("$f"); else ordered+=("$f"); fi
done
ordered+=("${tail_files[@]}")
total=${#ordered[@]}

# --- one run ----------------------------------------------------------------------------------
# Writes $tmp/rows/N.tsv: file, class, seconds, faces, bodies, substeps, overlaps, message.
md_cell() { sed 's/|/\\|/g; s/[[:cntrl:]]/ /g' <<<"$1"; }
run_one() {
  local n=$1 rel=$2 dir=$tmp/runs/$1
  mkdir -p "$dir"
  local start end rc=0
  start=$EPOCHREALTIME
  # The outer redirection takes bash's own "Segmentation fault" or "Killed" report of the child.
  {
    (
      if [ "$mem_mib" -gt 0 ]; then ulimit -v $((mem_mib * 1024)); fi
      exec timeout -k "$kill_after" "$limit" "$softbake" run "$corpus/$rel" --frames "$frames" \
        --no-render -j 1 -o "$dir/out"
    ) </dev/null >"$dir/stdout" 2>"$dir/stderr"
  } 2>/dev/null || rc=$?
  end=$EPOCHREALTIME
  local seconds
  seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')

  # The message: softbake's own error line, else the first line on stderr that is not blank.
  local message
  message=$(sed -n 's/^softbake: error: //p; T; q' "$dir/stderr")
  [ -n "$message" ] || message=$(grep -m1 -v '^[[:space:]]*$' "$dir/stderr" || true)
  message=${message//"$corpus/$rel: "/}
  message=${message//"$corpus/$rel"/FILE}
  message=${message//"$dir/out"/OUT}

  local class
  if [ "$rc" -eq 124 ] || { [ "$rc" -eq 137 ] && awk -v s="$seconds" -v l="$limit" 'BEGIN { exit !(s >= l) }'; }; then
    class='timed out'
    # How far it got: the scene line comes once the import is done.
    if grep -q "^scene '.*': [0-9]* bodies" "$dir/stdout"; then
      message="no result in $limit s (exit $rc), in the simulation"
    else
      message="no result in $limit s (exit $rc), still importing"
    fi
  elif [ "$rc" -eq 0 ]; then
    class=baked
    message=''
  elif grep -qi 'blew up\|blown up' "$dir/stderr"; then
    class='blew up'
  elif [ "$rc" -gt 128 ]; then
    class=crashed
    message="killed by SIG$(kill -l $((rc - 128)) 2>/dev/null || echo "$((rc - 128))")${message:+; $message}"
  elif grep -q 'assimp crashed reading the file' "$dir/stderr"; then
    class=crashed
  elif { [ "$rc" -eq 1 ] || [ "$rc" -eq 2 ]; } && [ -n "$message" ]; then
    class=refused
  else
    class=other
    message="exit $rc${message:+; $message}"
  fi

  local bodies='' faces='' substeps='' overlaps=''
  local manifest=$dir/out/manifest.json
  if [ -s "$manifest" ]; then
    bodies=$(jq -r '(.bodies // empty) | length' "$manifest" 2>/dev/null || true)
    faces=$(jq -r '[(.bodies // [])[] | (.triangles // .faces // empty)] | if length > 0 then add else empty end' \
      "$manifest" 2>/dev/null || true)
  fi
  local scene_line
  scene_line=$(grep -m1 "^scene '.*': [0-9]* bodies" "$dir/stdout" || true)
  [ -n "$bodies" ] || bodies=$(sed -n 's/.*: \([0-9]*\) bodies,.*/\1/p' <<<"$scene_line")
  [ -n "$faces" ] || faces=$(sed -n 's/.*, \([0-9]*\) triangles,.*/\1/p' <<<"$scene_line")
  # One simulated frame: the steps it took are its substeps; else what the run announced.
  substeps=$(sed -n "s/^wrote $frames frames .*, \([0-9]*\) steps, .*/\1/p; T; q" "$dir/stdout")
  [ -n "$substeps" ] || substeps=$(sed -n 's/^substeps: \([0-9]*\) per frame.*/\1/p; T; q' "$dir/stdout")
  overlaps=$(grep -m1 '^warning: surfaces intersect at the start' "$dir/stdout" |
    grep -o '([0-9]* triangle pairs)' | awk '{ s += substr($1, 2) } END { if (NR) print s }' || true)

  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$rel" "$class" "$seconds" "$faces" "$bodies" \
    "$substeps" "$overlaps" "$(md_cell "$message")" >"$tmp/rows/$n.tsv"
  printf '[%d/%d] %-9s %7s s  %s\n' "$n" "$total" "$class" "$seconds" "$rel" >&2
  rm -rf "$dir"
}

mkdir -p "$tmp/rows" "$tmp/runs"
started=$(date -u '+%Y-%m-%d %H:%M UTC')
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
begin=$EPOCHREALTIME
running=0
for i in "${!ordered[@]}"; do
  rel=${ordered[$i]}
  if [ -n "${is_last[$rel]:-}" ]; then  # alone, after everything else
    wait
    running=0
    run_one $((i + 1)) "$rel"
    continue
  fi
  if [ "$jobs" -le 1 ]; then
    run_one $((i + 1)) "$rel"
  else
    if [ "$running" -ge "$jobs" ]; then wait -n || true; running=$((running - 1)); fi
    run_one $((i + 1)) "$rel" &
    running=$((running + 1))
  fi
done
wait
elapsed=$(awk -v a="$begin" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.0f", b - a }')

# --- the table and the summary ----------------------------------------------------------------
rows=$tmp/rows.tsv
for i in $(seq 1 "$total"); do cat "$tmp/rows/$i.tsv"; done >"$rows"

summary() {
  local count
  printf '%d model files, %d s in all.\n\n' "$total" "$elapsed"
  printf '| outcome | files |\n|---|---:|\n'
  for class in baked refused 'timed out' crashed 'blew up' other; do
    count=$(awk -F'\t' -v c="$class" '$2 == c' "$rows" | wc -l)
    printf '| %s | %d |\n' "$class" "$count"
  done
  printf '\nThe slowest 10:\n\n| file | outcome | wall s | faces | bodies | substeps/frame | initial overlap pairs |\n'
  printf '|---|---|---:|---:|---:|---:|---:|\n'
  # awk, not head: head would leave sort writing into a closed pipe (and pipefail end the script).
  sort -t$'\t' -k3,3gr "$rows" |
    awk -F'\t' 'NR <= 10 { printf "| %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7 }'
}

commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
# Changes under bench/ (this script, its results) do not go into the binary.
if ! git -C "$root" diff --quiet HEAD -- . ":!bench" 2>/dev/null; then commit="$commit (with uncommitted changes)"; fi
# The command as given, with the settings that were set.
invocation=''
for v in SOFTBAKE CORPUS_TIMEOUT CORPUS_KILL_AFTER CORPUS_MEM_MIB CORPUS_LAST CORPUS_JOBS CORPUS_FILTER; do
  if [ -n "${!v+x}" ]; then invocation+="$v=$(printf '%q' "${!v}") "; fi
done
invocation+="bash $(printf '%q ' "$script" "${args[@]}")"
invocation=${invocation% }
mkdir -p "$(dirname "$table")"
q='`'  # Markdown's code quote
{
  printf '# assimp test corpus: softbake run, 2 frames, per file\n\n'
  printf 'Written by %sbench/corpus.sh%s (its header gives the file rule and the outcome classes).\n\n' \
    "$q" "$q"
  printf -- '- softbake: %s, commit %s\n' "${softbake#"$root/"}" "$commit"
  printf -- '- corpus: %s\n' "$corpus"
  # The assimp the binary loads, and the Debian package that holds it where there is one.
  lib=$(ldd "$softbake" 2>/dev/null | awk '/libassimp/ { print $3 }' || true)
  if [ -n "$lib" ]; then
    pkg=$(dpkg -S "$(readlink -f "$lib")" 2>/dev/null | cut -d: -f1-2 | head -1 || true)
    [ -z "$pkg" ] || pkg="$pkg $(dpkg-query -W -f '${Version}' "$pkg" 2>/dev/null || true)"
    printf -- '- assimp: %s%s\n' "$lib" "${pkg:+ ($pkg)}"
  fi
  printf -- '- machine: %s (nproc %s), %s GiB memory\n' "$(uname -srm)" "$(nproc)" \
    "$(awk '/MemTotal/ { printf "%.0f", $2 / 1048576 }' /proc/meminfo)"
  printf -- '- started: %s, load average %s; at the end %s\n' "$started" "$load_before" \
    "$(cut -d' ' -f1-3 /proc/loadavg)"
  printf -- '- command: %s%s%s (in %s)\n' "$q" "$invocation" "$q" "$PWD"
  printf -- '- each file: %stimeout -k %s %s softbake run FILE --frames %d --no-render -j 1 -o TMP%s' \
    "$q" "$kill_after" "$limit" "$frames" "$q"
  if [ "$mem_mib" -gt 0 ]; then
    printf ' under %sulimit -v %d%s (%d MiB)' "$q" $((mem_mib * 1024)) "$q" "$mem_mib"
  fi
  printf ', %d at a time' "$jobs"
  [ ${#tail_files[@]} -eq 0 ] || printf '; run last: %s' "${tail_files[*]}"
  printf '\n\nOutcomes: %sbaked%s exit 0; %srefused%s exit 1 or 2 with a message; %scrashed%s a signal, or\n' \
    "$q" "$q" "$q" "$q" "$q" "$q"
  printf 'assimp'"'"'s reading process crashed (softbake reads in a child process and then exits 1 with\n'
  printf '"assimp crashed reading the file"); %stimed out%s the limit; %sblew up%s the simulation blew up.\n' \
    "$q" "$q" "$q" "$q"
  printf 'Faces are triangles, after the import; substeps/frame is what the one simulated frame took\n'
  printf '(what the run announced, where it did not finish); initial overlap pairs are the triangle\n'
  printf 'pairs the run reported intersecting at the start.\n\n## Summary\n\n'
  summary
  printf '\n## Every file\n\n| file | outcome | wall s | faces | bodies | substeps/frame | initial overlap pairs | message |\n'
  printf '|---|---|---:|---:|---:|---:|---:|---|\n'
  LC_ALL=C sort -t$'\t' -k1,1 "$rows" |
    awk -F'\t' '{ printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8 }'
} >"$table"
summary
echo "table: $table"

#!/usr/bin/env bash
# ctest's smoke run of one benchmark program, so none of them rots: run it briefly, then check
# that it wrote its CSV with a header and at least one row of figures.
#   smoke.sh CSV HEADER_PREFIX PROGRAM [ARGS...]
set -euo pipefail
csv=$1 header=$2
shift 2
rm -f "$csv"
"$@" >/dev/null
[ -s "$csv" ] || { echo "smoke: $1 wrote no $csv" >&2; exit 1; }
# Google Benchmark puts its context lines first; the table starts at the header.
rows=$(awk -v h="$header" 'found { n++ } index($0, h) == 1 { found = 1 } END { print n + 0 }' "$csv")
[ "$rows" -ge 1 ] || { echo "smoke: $csv has no '$header' header followed by rows" >&2; exit 1; }
echo "smoke: $1: $rows rows in $csv"

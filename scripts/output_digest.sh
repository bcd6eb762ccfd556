#!/usr/bin/env bash
# Prints a SHA-256 per output file of every example, run to its last frame with every writer on
# (OBJ, contacts, VDB, PNG), and of the deterministic columns of `softbake bench` on fig7. Two
# builds whose digests are equal write byte-identical outputs: refactors show "behaviour
# unchanged" with it.
#   bash scripts/output_digest.sh BUILD_DIR WORK_DIR > digest.txt
#   diff before.txt after.txt
# A run that stops with an error (fig7 blows up at frame 13 today) is digested up to where it
# stopped, with its exit code, so a change in where it stops shows too.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:?usage: output_digest.sh BUILD_DIR WORK_DIR}
work=${2:?usage: output_digest.sh BUILD_DIR WORK_DIR}
softbake=$build/cli/softbake
rm -rf "$work" && mkdir -p "$work"

for scene in "$root"/examples/*.json; do
  name=$(basename "$scene" .json)
  out=$work/$name
  "$softbake" run "$scene" --out "$out" --render --vdb --contacts --quiet >"$work/$name.log" 2>&1
  echo "exit $? $name"
  (cd "$out" && find . -type f ! -name '.*' | LC_ALL=C sort | xargs sha256sum)
done

# bench: every column but the timings (contacts and pairs per step are exact).
csv=$work/fig7_bench.csv
"$softbake" bench "$root/examples/fig7_10k_faces.json" --steps 400 --broadphase sbhash,bvh \
  --csv "$csv" >"$work/bench.log" 2>&1
echo "exit $? bench"
head -n 1 "$csv"
python3 - "$csv" <<'EOF'
import csv, hashlib, sys
rows = list(csv.DictReader(open(sys.argv[1])))
timed = {c for c in rows[0] if c.endswith("_ms") or c.endswith("_s")}
kept = [c for c in rows[0] if c not in timed]
text = "\n".join(",".join(r[c] for c in kept) for r in rows)
print("bench columns kept:", ",".join(kept))
print("bench rows", len(rows), hashlib.sha256(text.encode()).hexdigest())
EOF

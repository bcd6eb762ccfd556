#!/usr/bin/env bash
# Prints a SHA-256 per output file of every example, run to its last frame with every writer on
# (OBJ, contacts, VDB, PNG), and of the deterministic columns of `softbake bench` on fig7. Two
# builds whose digests are equal write byte-identical outputs: refactors show "behaviour
# unchanged" with it.
#   bash scripts/output_digest.sh BUILD_DIR WORK_DIR > digest.txt
#   diff before.txt after.txt
# A run that stops with an error (fig7 blows up at frame 13 today) is digested up to where it
# stopped, with its exit code, so a change in where it stops shows too. Each .vdb file is hashed
# without the 36-character UUID that OpenVDB writes into every file header at random.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:?usage: output_digest.sh BUILD_DIR WORK_DIR}
work=${2:?usage: output_digest.sh BUILD_DIR WORK_DIR}
softbake=$build/cli/softbake
rm -rf "$work" && mkdir -p "$work"

digest_folder() {
  python3 - "$1" <<'PY'
import hashlib, os, sys
root = sys.argv[1]
paths = sorted(os.path.relpath(os.path.join(d, f), root)
               for d, _, files in os.walk(root) for f in files if not f.startswith("."))
for path in paths:
    data = bytearray(open(os.path.join(root, path), "rb").read())
    # OpenVDB's header: magic (8 bytes), file version (4), library version (8), grid-offsets
    # flag (1), then the file's random UUID as 36 ASCII characters.
    if path.endswith(".vdb") and data[:4] == b" BDV":
        data[21:57] = b"0" * 36
    print(hashlib.sha256(data).hexdigest(), " ./" + path)
PY
}

for scene in "$root"/examples/*.json; do
  name=$(basename "$scene" .json)
  out=$work/$name
  "$softbake" run "$scene" --out "$out" --render --vdb --contacts --quiet >"$work/$name.log" 2>&1
  echo "exit $? $name"
  digest_folder "$out"
done

# bench: every column but the timings (contacts and pairs per step are exact).
csv=$work/fig7_bench.csv
"$softbake" bench "$root/examples/fig7_10k_faces.json" --steps 400 --broadphase sbhash,bvh \
  --csv "$csv" >"$work/bench.log" 2>&1
echo "exit $? bench"
head -n 1 "$csv"
python3 - "$csv" <<'PY'
import csv, hashlib, sys
rows = list(csv.DictReader(open(sys.argv[1])))
timed = {c for c in rows[0] if c.endswith("_ms") or c.endswith("_s")}
kept = [c for c in rows[0] if c not in timed]
text = "\n".join(",".join(r[c] for c in kept) for r in rows)
print("bench columns kept:", ",".join(kept))
print("bench rows", len(rows), hashlib.sha256(text.encode()).hexdigest())
PY

#!/usr/bin/env bash
# How much of a bounce the integrator keeps at a given step: examples/fig5_ground.json (a rubber
# ball dropped from 2 m onto a ground of restitution 0.3) baked at several fixed substep counts,
# and the highest its centre rises again within 30 frames of its first landing. Backward Euler
# damps motion by a share that grows with the step, so the rise at the default substeps against
# the rise at many tells what the default costs in motion, where a resting state does not.
#   bash bench/bounce.sh [BUILD_DIR] [INTEGRATOR] [SUBSTEPS...]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
integrator=${2:-implicit}
shift $(($# > 2 ? 2 : $#))
counts=("$@")
((${#counts[@]})) || counts=(1 2 4 8 32 128)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "substeps,landing_frame,apex_m,rise_m"
for n in "${counts[@]}"; do
  "$build/cli/softbake" run "$root/examples/fig5_ground.json" --frames 72 --substeps "$n" \
    --integrator "$integrator" --no-render -j 2 -q -o "$work/s$n" >/dev/null
  python3 - "$work/s$n/obj" "$n" <<'EOF'
import glob, sys
centres, lowest = [], []
for path in sorted(glob.glob(sys.argv[1] + "/*.obj")):
    ys = [float(line.split()[2]) for line in open(path) if line.startswith("v ")]
    centres.append(sum(ys) / len(ys))
    lowest.append(min(ys))
landing = next(k for k, y in enumerate(lowest) if y < 0.02)
apex = max(centres[landing:landing + 30])
radius = 0.5  # the example's icosphere; its centre rests about this high
print(f"{sys.argv[2]},{landing + 1},{apex:.3f},{apex - radius:.3f}")
EOF
done

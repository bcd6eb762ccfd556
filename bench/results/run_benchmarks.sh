#!/bin/sh
# Runs the three benchmark programs and writes their JSON next to this script.
# Usage: bench/results/run_benchmarks.sh [build dir, default build-bench]
# The float and double stage programs alternate stage by stage, so both builds of one stage are
# timed within a minute of each other: on a shared machine the load changes faster than a full run.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build-bench}
out=$root/bench/results
flags="--benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_min_time=0.2"
for stage in SpringForces Volumes PressureForces Integrate PlaneContacts Step; do
  for program in core_stages_bench core_stages_bench_double; do
    "$build/bench/$program" $flags --benchmark_filter="^BM_$stage/" \
      --benchmark_out="$out/$program.$stage.json" --benchmark_out_format=json
  done
done
"$build/bench/layout_bench" $flags --benchmark_out="$out/layout_bench.json" \
  --benchmark_out_format=json

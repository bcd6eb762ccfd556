#!/usr/bin/env python3
"""Prints the Markdown tables of bench/results/README.md from the JSON run_benchmarks.sh wrote."""
import glob
import json
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))


def aggregates(paths):
    """{run_name: {aggregate_name: benchmark entry}} over every JSON file given."""
    runs = {}
    for path in paths:
        with open(path) as f:
            for b in json.load(f)["benchmarks"]:
                if b.get("run_type") == "aggregate":
                    runs.setdefault(b["run_name"], {})[b["aggregate_name"]] = b
    return runs


def cell(run):
    """Median µs, with the coefficient of variation of the five repetitions."""
    if run is None:
        return "–"
    return f"{run['median']['real_time']:,.1f} ({100 * run['cv']['real_time']:.0f}%)"


def ratio(a, b):
    return f"{b['median']['real_time'] / a['median']['real_time']:.2f}" if a and b else "–"


def stages():
    single = aggregates(glob.glob(os.path.join(HERE, "core_stages_bench.*.json")))
    double = aggregates(glob.glob(os.path.join(HERE, "core_stages_bench_double.*.json")))
    print("| stage | faces | float 1T | float 2T | double 1T | double 2T | double/float 1T | "
          "double/float 2T | float 1T Mfaces/s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, run in single.items():
        m = re.match(r"BM_(\w+)/faces:(\d+)/threads:1/", name)
        if not m:
            continue
        two = name.replace("threads:1", "threads:2")
        rate = run["median"]["items_per_second"] / 1e6
        print(f"| {m[1]} | {int(m[2]):,} | {cell(run)} | {cell(single.get(two))} | "
              f"{cell(double.get(name))} | {cell(double.get(two))} | {ratio(run, double.get(name))} | "
              f"{ratio(single.get(two), double.get(two))} | {rate:,.0f} |")


def layouts():
    runs = aggregates([os.path.join(HERE, "layout_bench.json")])
    print("| pass | faces | packed xyz | Eigen 3×N | split x/y/z | 3×N / packed | split / packed |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, run in runs.items():
        m = re.match(r"BM_Layout/(\w+)/packed/faces:(\d+)/", name)
        if not m:
            continue
        eigen, split = runs.get(name.replace("packed", "eigen3n")), runs.get(name.replace("packed", "split"))
        print(f"| {m[1]} | {int(m[2]):,} | {cell(run)} | {cell(eigen)} | {cell(split)} | "
              f"{ratio(run, eigen)} | {ratio(run, split)} |")


if __name__ == "__main__":
    stages()
    print()
    layouts()

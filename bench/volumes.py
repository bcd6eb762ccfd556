#!/usr/bin/env python3
"""Each closed body's worst volume change over a bake, against the issue 34 limits.

    python3 bench/volumes.py OUT [OUT ...]

OUT is the folder of a `softbake run SCENE ... --report DIR` (its frame_stats.jsonl holds every
body's volume per frame), and SCENE.json, the scene as `softbake scene SCENE` prints it, is beside
it (OUT.scene.json) or is the run's input: it names each body's material. A body's rest volume is
its volume at frame 1, the initial state. Prints one Markdown row per body: scene, body,
material, bulk modulus, the worst change and its frame, and whether it is within the limit its
preset promises (rubber and stiff 5%, jelly 10%; bodies of gas alone, bulk modulus 0, follow
their load by design and have no limit). Exits 1 when a body is past its limit.
"""
import json
import math
import pathlib
import sys

LIMITS = {"rubber": 0.05, "stiff": 0.05, "jelly": 0.10}
# The presets' bulk moduli, Pa (docs/materials.md), for bodies that do not override theirs.
PRESET_BULK = {"stiff": 80000, "rubber": 40000, "jelly": 8000, "balloon": 0}


def bodies_of(scene):
    for body in scene.get("bodies", []):
        material = body.get("material", "rubber")
        if isinstance(material, dict):
            preset = material.get("preset", "rubber")
            bulk = material.get("bulk_modulus", PRESET_BULK.get(preset))
        else:
            preset, bulk = material, PRESET_BULK.get(material)
        yield body.get("name", "?"), preset, bulk


def scene_of(out, manifest):
    beside = out.with_name(out.name + ".scene.json")
    if beside.exists():
        return json.loads(beside.read_text())
    return json.loads(pathlib.Path(manifest["run"]["input"]).read_text())


def main(outs):
    failed = False
    print("| scene | body | material | bulk modulus Pa | worst volume change | at frame | limit | within |")
    print("|---|---|---|---:|---:|---:|---:|---|")
    for out in map(pathlib.Path, outs):
        manifest = json.loads((out / "manifest.json").read_text())
        frames = [json.loads(line) for line in (out / "frame_stats.jsonl").read_text().splitlines()
                  if line.strip()]
        frames.sort(key=lambda f: f["frame"])
        rest = frames[0]["volumes"]
        names = list(bodies_of(scene_of(out, manifest)))
        scene = manifest.get("scene") or out.name
        for b, v0 in enumerate(rest):
            if v0 is None or not v0 > 0:
                continue
            worst, at = 0.0, frames[0]["frame"]
            for f in frames[1:]:
                v = f["volumes"][b]
                change = math.inf if v is None else v / v0 - 1
                if abs(change) > abs(worst):
                    worst, at = change, f["frame"]
            name, preset, bulk = names[b] if b < len(names) else (f"body {b}", "?", None)
            limit = LIMITS.get(preset) if bulk != 0 else None
            ok = limit is None or abs(worst) <= limit
            failed |= not ok
            print(f"| {scene} | {name} | {preset} | {'' if bulk is None else bulk} | "
                  f"{100 * worst:+.2f}% | {at} | {'' if limit is None else f'{100 * limit:.0f}%'} | "
                  f"{'yes' if ok else '**no**'} |")
    return 1 if failed else 0


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1:]))

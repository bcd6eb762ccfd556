#!/usr/bin/env python3
"""Writes pile64.json: 64 balls of every preset and masses 0.2-2 kg (1:10), in four layers of
4x4 from 1.2 m to 4.8 m up, dropped onto a static sphere and the ground (the contacts issue's
"piles": 8 to 64 bodies, mass ratios up to 1:10, drops from up to 5 m onto a static mesh).
    python3 bench/scenes/make_pile64.py > bench/scenes/pile64.json"""
import json

presets = ["stiff", "rubber", "jelly", "balloon"]
masses = [0.2, 0.5, 1.0, 2.0]
bodies = []
for layer in range(4):
    for row in range(4):
        for column in range(4):
            k = len(bodies)
            # Alternate layers are offset by a quarter cell, so balls land on balls, not in gaps.
            shift = 0.15 if layer % 2 else 0.0
            bodies.append({
                "name": f"b{k:02d}",
                "mesh": {"primitive": "icosphere", "subdivisions": 2, "radius": 0.25},
                "transform": {"translate": [round(-0.9 + 0.6 * column + shift, 3),
                                            round(1.2 + 1.2 * layer, 3),
                                            round(-0.9 + 0.6 * row + shift, 3)]},
                "material": presets[(k + layer) % 4],
                "mass": masses[(k // 4 + row) % 4],
                # Balls under others crease into themselves without it (909 pairs within bodies).
                "self_collision": True,
            })
scene = {
    "name": "pile64",
    "settings": {"fps": 24, "frames": 120},
    "bodies": bodies,
    "colliders": [
        {"type": "mesh", "name": "sphere",
         "mesh": {"primitive": "icosphere", "subdivisions": 4, "radius": 0.6},
         "transform": {"translate": [0, 0.3, 0]}},
        {"type": "plane", "name": "ground"},
    ],
}
print(json.dumps(scene, indent=1))

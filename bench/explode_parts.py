"""The same assembly with its parts apart: every mesh object of a glTF file moved away from the
assembly's centre, so that no two parts touch or overlap. bench/results/assemblies.md compares a
step of an assembly whose parts overlap by design with a step of the same parts apart.

    blender -b --factory-startup --python bench/explode_parts.py -- IN.glb OUT.glb FACTOR

FACTOR scales each part's offset from the centre of all parts (3: three times as far out).
"""
import sys

import numpy

# Blender 3.4's glTF importer still uses numpy.bool, which Debian 12's numpy no longer has.
if "bool" not in vars(numpy):
    numpy.bool = bool

import bpy  # noqa: E402
import mathutils  # noqa: E402


def centre(obj):
    corners = [obj.matrix_world @ mathutils.Vector(c) for c in obj.bound_box]
    return sum(corners, mathutils.Vector()) / len(corners)


def main():
    source, target, factor = sys.argv[sys.argv.index("--") + 1:][:3]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=source)
    parts = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    middle = sum((centre(o) for o in parts), mathutils.Vector()) / len(parts)
    for part in parts:
        offset = (centre(part) - middle) * (float(factor) - 1)
        part.matrix_world = mathutils.Matrix.Translation(offset) @ part.matrix_world
    bpy.ops.export_scene.gltf(filepath=target, export_format="GLB")
    print(f"explode_parts: {len(parts)} parts moved apart by {factor}x into {target}")


main()

# SPDX-License-Identifier: MIT
"""Checks the softbake Blender add-on inside Blender (headless):

    blender -b --factory-startup --python-exit-code 1 --python dcc/blender/check_import.py -- \
        --addon-zip softbake_blender.zip --manifest OUT/manifest.json [--frames 1,60,240] \
        [--check-errors] [--timing-only]

Installs and enables the add-on from the zip, imports the manifest with
bpy.ops.import_scene.softbake and times it, then checks, independently of the add-on's code:

  * every body of the manifest is a mesh object of the new collection whose evaluated mesh
    (Mesh Cache modifier applied), in world space, equals at each --frames frame the vertices of
    that body's `o` block in the OBJ sequence's frame, within --tolerance (the OBJ sequence is
    Y-up, so (x, y, z) is compared as (x, -z, y) with Blender's Z-up world);
  * the Volume object exists, points at the VDB sequence (first frame, is_sequence, start and
    duration) and loads the right file at each frame;
  * the scene's frame range and frame rate are the manifest's;
  * with --check-errors: a missing manifest, a missing rest mesh and a point cache whose vertex
    count differs from its rest mesh are refused with an error naming the file, creating nothing.

--timing-only imports, prints the import time, checks the vertex and face counts of every body
and times the first evaluation (which reads every point cache), without the per-frame comparison.

Exits 0 after a final "PASS" line, 1 on the first failed check ("FAIL: ...").
"""

import argparse
import json
import os
import shutil
import struct
import sys
import tempfile
import time
import traceback

import bpy
import mathutils


class CheckFailed(Exception):
    pass


def check(condition, message):
    if not condition:
        raise CheckFailed(message)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="check_import.py")
    p.add_argument("--addon-zip", help="install and enable the add-on from this zip first")
    p.add_argument("--manifest", required=True)
    p.add_argument("--frames", default="1,60,240", help="frames to compare (default %(default)s)")
    p.add_argument("--tolerance", type=float, default=1e-5)
    p.add_argument("--check-errors", action="store_true")
    p.add_argument("--timing-only", action="store_true")
    return p.parse_args(argv)


def install_addon(zip_path):
    t = time.perf_counter()
    result = bpy.ops.preferences.addon_install(filepath=os.path.abspath(zip_path), overwrite=True)
    check(result == {'FINISHED'}, "addon_install(%r) returned %r" % (zip_path, result))
    result = bpy.ops.preferences.addon_enable(module="softbake_blender")
    check(result == {'FINISHED'}, "addon_enable('softbake_blender') returned %r" % (result,))
    check(hasattr(bpy.types, "IMPORT_SCENE_OT_softbake"), "the operator is not registered")
    print("check: add-on installed and enabled in %.2f s" % (time.perf_counter() - t))


def import_bake(manifest):
    """Runs the operator; returns (the new collection, seconds)."""
    before = set(bpy.data.collections)
    t = time.perf_counter()
    result = bpy.ops.import_scene.softbake(filepath=manifest)
    seconds = time.perf_counter() - t
    check(result == {'FINISHED'}, "import_scene.softbake returned %r" % (result,))
    new = [c for c in bpy.data.collections if c not in before]
    check(len(new) == 1, "expected one new collection, got %r" % [c.name for c in new])
    return new[0], seconds


def obj_frame_bodies(path):
    """{body: [(x, y, z), ...]} from the `v` lines of each `o` block of an OBJ frame."""
    bodies = {}
    current = None
    with open(path, "r", encoding="utf-8") as f:
        for line in f:
            if line.startswith("o "):
                current = bodies.setdefault(line[2:].strip(), [])
            elif line.startswith("v "):
                check(current is not None, "%s: a vertex before any 'o' line" % path)
                # As float32, the precision softbake simulates and writes in: the text is the
                # shortest that reads back to the float32, not the float32's exact decimal value.
                x, y, z = struct.unpack("<3f", struct.pack("<3f", *map(float, line.split()[1:4])))
                current.append((x, y, z))
    return bodies


def sequence(manifest, fmt):
    for seq in manifest.get("sequences", []):
        if seq.get("format") == fmt:
            return seq
    return None


def body_objects(collection, manifest):
    objects = {}
    for body in manifest["bodies"]:
        name = body["name"]
        # Blender may add ".001" to a name already taken in the .blend file.
        matches = [o for o in collection.objects if o.type == 'MESH'
                   and (o.name == name or (o.name.rpartition(".")[0] == name
                                           and o.name.rpartition(".")[2].isdigit()))]
        check(len(matches) == 1, "body '%s': %d mesh objects in collection '%s'"
              % (name, len(matches), collection.name))
        obj = matches[0]
        check(len(obj.data.vertices) == body["particles"],
              "body '%s': %d vertices, the manifest says %d particles"
              % (name, len(obj.data.vertices), body["particles"]))
        if "triangles" in body:
            check(len(obj.data.polygons) == body["triangles"],
                  "body '%s': %d faces, the manifest says %d triangles"
                  % (name, len(obj.data.polygons), body["triangles"]))
        caches = [m for m in obj.modifiers if m.type == 'MESH_CACHE']
        check(len(caches) == 1, "body '%s': %d Mesh Cache modifiers" % (name, len(caches)))
        objects[name] = obj
    return objects


def check_positions(manifest, folder, objects, frames, tolerance):
    scene = bpy.context.scene
    obj_seq = sequence(manifest, "obj")
    check(obj_seq is not None, "the manifest lists no OBJ sequence to compare with")
    worst = 0.0
    for frame in frames:
        scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        reference = obj_frame_bodies(os.path.join(folder, obj_seq["printf_pattern"] % frame))
        for name, obj in objects.items():
            check(name in reference, "frame %d: no 'o %s' block in the OBJ frame" % (frame, name))
            ev = obj.evaluated_get(depsgraph)
            mesh = ev.data
            mw = ev.matrix_world
            ref = reference[name]
            check(len(mesh.vertices) == len(ref), "frame %d, body '%s': %d evaluated vertices, "
                  "the OBJ frame has %d" % (frame, name, len(mesh.vertices), len(ref)))
            for i, v in enumerate(mesh.vertices):
                w = mw @ v.co
                x, y, z = ref[i]
                d = max(abs(w.x - x), abs(w.y - (-z)), abs(w.z - y))
                if d > worst:
                    worst = d
                check(d <= tolerance,
                      "frame %d, body '%s', vertex %d: Blender has (%.7g, %.7g, %.7g), the OBJ "
                      "frame (x, -z, y) = (%.7g, %.7g, %.7g): off by %.3g"
                      % (frame, name, i, w.x, w.y, w.z, x, -z, y, d))
        print("check: frame %d: %d bodies match the OBJ frame" % (frame, len(objects)))
    print("check: largest difference over frames %s: %.3g (tolerance %g)"
          % (",".join(map(str, frames)), worst, tolerance))


def check_volume(manifest, folder, collection, frames):
    vdb = sequence(manifest, "vdb")
    volumes = [o for o in collection.objects if o.type == 'VOLUME']
    if vdb is None:
        check(not volumes, "no VDB sequence in the manifest, but a Volume object was made")
        print("check: no VDB sequence, no Volume object")
        return
    check(len(volumes) == 1, "expected one Volume object, got %d" % len(volumes))
    obj = volumes[0]
    vol = obj.data
    first = manifest.get("first_frame", 1)
    expected = os.path.normpath(os.path.join(folder, vdb["printf_pattern"] % first))
    actual = os.path.normpath(bpy.path.abspath(vol.filepath))
    check(actual == expected, "volume filepath %r, expected %r" % (actual, expected))
    check(vol.is_sequence, "the volume is not a sequence")
    check(vol.frame_start == first, "volume frame_start %d, expected %d" % (vol.frame_start, first))
    check(vol.frame_duration == manifest["frames"], "volume frame_duration %d, expected %d"
          % (vol.frame_duration, manifest["frames"]))
    scene = bpy.context.scene
    for frame in frames:
        scene.frame_set(frame)
        ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        grids = ev.data.grids
        grids.load()
        want = os.path.normpath(os.path.join(folder, vdb["printf_pattern"] % frame))
        got = os.path.normpath(bpy.path.abspath(grids.frame_filepath))
        check(got == want, "frame %d: the volume loads %r, expected %r" % (frame, got, want))
        check(grids.is_loaded and not grids.error_message,
              "frame %d: the volume's grids did not load: %s" % (frame, grids.error_message))
        names = sorted(g.name for g in grids)
        check_volume_bounds(frame, ev, collection)
        bodies = [b["name"] for b in manifest["bodies"]]
        surfaces = ["surface"] if len(bodies) == 1 else [b + "_surface" for b in bodies]
        for s in surfaces:
            check(s in names or s + "_udf" in names,
                  "frame %d: no grid %r in the volume (grids %r)" % (frame, s, names))
    print("check: Volume '%s' plays %s from frame %d for %d frames (grids %s)"
          % (obj.name, vdb["pattern"], first, manifest["frames"], ", ".join(names)))


def world_bounds(obj_eval):
    points = [obj_eval.matrix_world @ mathutils.Vector(c) for c in obj_eval.bound_box]
    return ([min(p[i] for p in points) for i in range(3)],
            [max(p[i] for p in points) for i in range(3)])


def check_volume_bounds(frame, volume_eval, collection):
    """The level sets' box must hold the bodies' box, a narrow band wider on each side: this
    checks the volume's axes against the meshes' (a Y-up volume left unturned would not fit)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    meshes = [o.evaluated_get(depsgraph) for o in collection.objects if o.type == 'MESH']
    if not meshes:
        return
    lo = [min(world_bounds(m)[0][i] for m in meshes) for i in range(3)]
    hi = [max(world_bounds(m)[1][i] for m in meshes) for i in range(3)]
    vlo, vhi = world_bounds(volume_eval)
    size = max(h - l for l, h in zip(lo, hi))
    # Blender's volume box is that of the grids' leaf nodes (8^3 voxels), so it passes the 3-voxel
    # narrow band by up to 8 more voxels (of half the mean edge length), unevenly; a turn of the
    # axes would be off by the whole height of the scene.
    band = 0.25 * size
    for i in range(3):
        check(vlo[i] <= lo[i] + 1e-6 and vhi[i] >= hi[i] - 1e-6
              and lo[i] - vlo[i] <= band and vhi[i] - hi[i] <= band,
              "frame %d: the volume's box %s-%s does not fit the bodies' box %s-%s (axis %s)"
              % (frame, vlo, vhi, lo, hi, "xyz"[i]))


def check_scene(manifest):
    scene = bpy.context.scene
    first = manifest.get("first_frame", 1)
    last = first + manifest["frames"] - 1
    check((scene.frame_start, scene.frame_end) == (first, last), "scene frames %d-%d, expected %d-%d"
          % (scene.frame_start, scene.frame_end, first, last))
    fps = scene.render.fps / scene.render.fps_base
    check(abs(fps - manifest["fps"]) <= 1e-6 * manifest["fps"],
          "scene fps %g (%d / %g), expected %g"
          % (fps, scene.render.fps, scene.render.fps_base, manifest["fps"]))
    print("check: scene frames %d-%d at %g fps" % (first, last, fps))


def expect_refused(filepath, must_name, what):
    """The operator must fail with an error naming `must_name` and create nothing."""
    counts = (len(bpy.data.objects), len(bpy.data.collections), len(bpy.data.meshes),
              len(bpy.data.volumes))
    try:
        result = bpy.ops.import_scene.softbake(filepath=filepath)
    except RuntimeError as e:
        message = str(e)
    else:
        raise CheckFailed("%s: the import returned %r instead of an error" % (what, result))
    check(must_name in message, "%s: the error does not name %r: %s" % (what, must_name, message))
    after = (len(bpy.data.objects), len(bpy.data.collections), len(bpy.data.meshes),
             len(bpy.data.volumes))
    check(after == counts, "%s: the failed import created data-blocks" % what)
    print("check: %s is refused: %s" % (what, message.strip().splitlines()[0]))


def check_errors(manifest, folder):
    print("check: three broken bakes follow; the 'Error:' lines Blender prints for them are "
          "expected")
    work = tempfile.mkdtemp(prefix="softbake_check_")
    try:
        missing = os.path.join(work, "nowhere", "manifest.json")
        expect_refused(missing, missing, "a missing manifest")

        # A copy of the bake's point caches only (no VDB), to break one file at a time.
        entry = manifest["point_caches"][0]
        cache_key = "pc2" if entry.get("pc2") else "mdd"
        copy = dict(manifest)
        copy["sequences"] = [s for s in manifest.get("sequences", []) if s["format"] == "obj"]
        for e in manifest["point_caches"]:
            for key in ("mesh", "pc2", "mdd"):
                if e.get(key):
                    os.makedirs(os.path.join(work, os.path.dirname(e[key])), exist_ok=True)
                    shutil.copyfile(os.path.join(folder, e[key]), os.path.join(work, e[key]))
        copy_manifest = os.path.join(work, "manifest.json")
        with open(copy_manifest, "w") as f:
            json.dump(copy, f)

        cache = os.path.join(work, entry[cache_key])
        with open(cache, "rb") as f:
            data = f.read()
        if cache_key == "pc2":
            # A valid PC2 with the last point of every sample dropped.
            points, start, rate, samples = struct.unpack("<iffi", data[16:32])
            out = bytearray(data[:12] + struct.pack("<iiffi", 1, points - 1, start, rate, samples))
            for s in range(samples):
                base = 32 + 12 * points * s
                out += data[base:base + 12 * (points - 1)]
        else:
            frames, points = struct.unpack(">ii", data[:8])
            out = bytearray(struct.pack(">ii", frames, points - 1) + data[8:8 + 4 * frames])
            for s in range(frames):
                base = 8 + 4 * frames + 12 * points * s
                out += data[base:base + 12 * (points - 1)]
        with open(cache, "wb") as f:
            f.write(out)
        expect_refused(copy_manifest, os.path.normpath(cache),
                       "a point cache with one point fewer than its rest mesh")
        with open(cache, "wb") as f:
            f.write(data)

        rest = os.path.normpath(os.path.join(work, entry["mesh"]))
        os.unlink(rest)
        expect_refused(copy_manifest, rest, "a missing rest mesh")
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main():
    args = parse_args()
    manifest_path = os.path.abspath(args.manifest)
    with open(manifest_path, "r", encoding="utf-8") as f:
        manifest = json.load(f)
    folder = os.path.dirname(manifest_path)
    frames = [int(x) for x in args.frames.split(",") if x.strip()]

    if args.addon_zip:
        install_addon(args.addon_zip)

    collection, seconds = import_bake(manifest_path)
    faces = sum(b.get("triangles", 0) for b in manifest["bodies"])
    vertices = sum(b["particles"] for b in manifest["bodies"])
    print("IMPORT TIME: %.3f s for scene '%s' (%d bodies, %d vertices, %d faces, %d frames)"
          % (seconds, manifest["scene"], len(manifest["bodies"]), vertices, faces,
             manifest["frames"]))
    check(collection.name.split(".")[0] == manifest["scene"],
          "the collection is named %r, not after the scene %r" % (collection.name,
                                                                  manifest["scene"]))

    objects = body_objects(collection, manifest)
    print("check: %d body objects with their vertex and face counts" % len(objects))
    check_scene(manifest)

    if args.timing_only:
        scene = bpy.context.scene
        t = time.perf_counter()
        scene.frame_set(scene.frame_start)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        evaluated = sum(len(o.evaluated_get(depsgraph).data.vertices) for o in objects.values())
        print("FIRST EVALUATION: %.3f s (%d vertices read from the point caches)"
              % (time.perf_counter() - t, evaluated))
        check(evaluated == vertices, "%d evaluated vertices, expected %d" % (evaluated, vertices))
    else:
        check_positions(manifest, folder, objects, frames, args.tolerance)
        check_volume(manifest, folder, collection, frames)
        if args.check_errors:
            check_errors(manifest, folder)
    print("PASS: softbake add-on import of '%s'%s" % (manifest_path,
          " (timing only)" if args.timing_only else ""))


try:
    main()
except CheckFailed as e:
    print("FAIL: %s" % e, flush=True)
    sys.exit(1)
except SystemExit:
    raise
except BaseException:
    traceback.print_exc()
    print("FAIL: unexpected error (above)", flush=True)
    sys.exit(1)
sys.stdout.flush()

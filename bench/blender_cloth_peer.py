"""Peer benchmark: the same softbake scene in Blender's cloth simulator with pressure.

    blender -b --factory-startup --python bench/blender_cloth_peer.py -- SCENE.json \
        [--frames N] [--quality Q] [--base-dir DIR]

SCENE.json is softbake's scene JSON, best as `softbake scene NAME_OR_FILE` prints it (plain JSON,
no comments; bench/blender_peer.sh does that). Mesh paths are relative to --base-dir (default:
the folder of SCENE.json). The script builds the scene in Blender, simulates frames 1..N with
scene.frame_set and prints ONE machine-readable line on stdout:

    peer=blender_cloth scene=balls10k faces=10240 frames=24 seconds=... frames_per_s=...
        quality=5 volume_ratio_min=... threads=2

frames=N is counted as softbake counts it: frame 1 is the initial state, so N-1 frames are
simulated, and frames_per_s = (N-1) / seconds, comparable with `softbake bench SCENE --frames N`.
seconds is the wall time of frame_set(2..N) only: building the scene and the cloth's
initialisation on frame 1 are not in it. volume_ratio_min is the smallest final / rest enclosed
volume over the bodies (evaluated mesh, bmesh calc_volume), to compare roundness. Each body's
final centre height, lowest point and volume ratio go to stderr. Blender uses its default thread
count (all cores).

What is the same: every body is the same triangle mesh (a softbake icosphere of `subdivisions` s
is Blender's icosphere of s+1, 20*4^s faces, checked; OBJ, PLY and STL files are imported with
their axes unchanged, welded and triangulated), placed by the same transform, with the same mass
(body mass / vertex count per vertex), gas pressure, gravity, frame rate and frame count, over the
same ground plane (a large plane object with a Collision modifier) and static mesh colliders.
Coordinates are used as they are (softbake is y-up; Blender's cloth takes gravity as a vector).

How softbake's parameters become Blender's (u = 1/fps s; Blender's cloth clock counts frames,
ignoring fps, and scales gravity by 0.001, so every value is converted to kg, m and u):

  gravity          scene.gravity = g * u^2 / 0.001, so the cloth sees g per frame^2.
  vertex_mass      body mass / vertex count (softbake spreads it by vertex area; alike on
                   icospheres).
  tension, compression stiffness
                   Blender's spring constant is stiffness / mean edge length, so
                   stiffness = k_eff * u^2 * mean edge length, with k_eff = stiffness +
                   3 * bend_stiffness (on equilateral triangles; the mesh's sum of d^2 / sum
                   of L^2 in general). Why: softbake's bending springs join the opposite
                   corners d of two triangles (about sqrt(3) edges L). On a closed, nearly
                   flat surface they resist stretching to first order but folding only by the
                   small dihedral angle, so under the uniform stretch that pressure causes they
                   act like extra edge springs of 3 * bend_stiffness. With that, a body inflates
                   to the same size in both (balls1k, 24 frames: balloon volume ratio 1.50 in
                   softbake, 1.52 here; fig5's rubber ball in flight 1.023 in both).
  bending_stiffness
                   (angular model, Blender's default) matched hinge by hinge to the fold
                   stiffness softbake's bending springs have at the rest shape,
                   bend_stiffness * (h_a h_b sin(angle) / d)^2, against Blender's
                   0.1 * stiffness * edge length * wing height; tiny on spheres.
  damping          softbake's fraction of critical damping per spring becomes the same
                   fraction of 2 sqrt(k m / 2) of the equivalent spring (tension, compression),
                   and of each hinge (bending).
  pressure         use_pressure on, uniform_pressure_force = 1 and pressure_factor = pressure *
                   u^2: Blender applies (V_rest / V - 1 + uniform) * factor per area, which is
                   then pressure * V_rest / V, softbake's gas law (nRT = pressure * V_rest).
                   Open meshes get no pressure, as in softbake.
  friction         Blender's Coulomb coefficient is 0.01 * cloth_friction (colliders) or
                   self_friction, so both are 100 * softbake's friction (at most 80): each plane
                   or mesh collider's own, settings.collisions.friction between soft bodies.
  distances        Blender's defaults: distance_min and self_distance_min 15 mm, Collision
                   outer thickness 20 mm. softbake's skin (1 mm) is too thin for Blender's
                   proximity test (with 1 mm + 1 mm, fig5's ball fell through the ground).
                   The ground plane and mesh colliders are moved in along their normals by
                   15 + 20 mm - skin, so bodies rest where they rest in softbake.
  quality          --quality Q steps per frame (default 5); collision quality stays at
                   Blender's default 2. Air damping 0: softbake has no drag.

Differences that remain, and cannot be made equal:
  * No initial velocity: Blender cloth starts at rest, so bodies with a `velocity` only fall.
  * Integrator: Blender solves backward Euler with a conjugate-gradient solve per step (Baraff &
    Witkin); softbake's default is explicit Euler with many more, smaller substeps
    (`substeps` and `integrator` are ignored here).
  * Springs: Blender's compression springs follow Choi & Ko's buckling model (no stiffer than
    Hookean), its bending springs are angular, and it has no bending springs across edges, so
    the mapping above matches softbake only for uniform stretch and small folds.
  * Mass is per vertex, uniform, not by vertex area.
  * Collisions: Blender keeps vertices a distance away from colliders and other cloth (proximity
    impulses, checked at the end of each step, `collision_quality` passes), with no restitution
    (normal velocity is stopped); softbake tests each particle's motion against the triangles
    (line-triangle, Mesit & Guha) and keeps `restitution`. Soft bodies collide through each
    other's Collision modifier, evaluated one after the other (Blender reports the dependency
    cycle), not in one simultaneous response. Colliders are single sided (use_normal).
  * Soft bodies stay 35 mm apart (15 mm distance + 20 mm thickness) instead of softbake's skin,
    so bodies that start closer (the balls* scenes' layers are 2 mm apart) are pushed apart from
    the first frame. Mesh colliders are inset along vertex normals, which is exact for planes
    and close for smooth meshes.
  * Self-collision is on for every body (as artists set it) unless the body says
    `"self_collision": false`; softbake's default is off for closed bodies, so Blender does
    that extra work.
  * The ground is a finite plane (large compared with the scene), not an infinite one.
  * Pins: boxes pin through Blender's pin group; `pins.indices` (the file's vertex numbers,
    which this script does not carry through Blender's importers), `pins.particles` (softbake's
    welded order) and mesh formats other than OBJ, PLY and STL are unsupported: the script names
    those bodies and exits with status 2.
"""

import argparse
import json
import math
import os
import sys
import time

import bmesh
import bpy
from mathutils import Euler, Matrix, Vector

# softbake's presets, core/scene/material.cpp: stiffness N/m, bend_stiffness N/m,
# damping (fraction of critical), pressure Pa.
PRESETS = {
    "stiff": (5000.0, 2500.0, 0.10, 300.0),
    "rubber": (1000.0, 300.0, 0.05, 100.0),
    "jelly": (150.0, 40.0, 0.03, 15.0),
    "balloon": (250.0, 5.0, 0.03, 400.0),
}
DEFAULT_SKIN = 0.001
DEFAULT_FRICTION = 0.3
# Blender's default collision distances, as artists leave them: a vertex is pushed out when it
# comes within CLOTH_DISTANCE + the collider's COLLIDER_THICKNESS. softbake's 1 mm skin is too
# thin for Blender's proximity test: with 1 mm + 1 mm, fig5's ball fell through the ground.
CLOTH_DISTANCE = 0.015
COLLIDER_THICKNESS = 0.02
BLENDER_GRAVITY_SCALE = 0.001  # cloth_calc_force multiplies scene gravity by this
IMPORTERS = {".obj", ".ply", ".stl"}


class Unsupported(Exception):
    """A part of the scene this peer cannot build in Blender."""


def log(message):
    print("blender_cloth_peer: " + message, file=sys.stderr, flush=True)


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="blender_cloth_peer.py")
    parser.add_argument("scene", help="softbake scene JSON (as `softbake scene` prints it)")
    parser.add_argument("--frames", type=int, help="frame count (default: the scene's)")
    parser.add_argument("--quality", type=int, default=5, help="cloth steps per frame")
    parser.add_argument("--base-dir", help="folder mesh paths are relative to")
    arguments = parser.parse_args(argv)
    if arguments.frames is not None and arguments.frames < 2:
        parser.error("--frames must be at least 2")
    if arguments.quality < 1:
        parser.error("--quality must be at least 1")
    return arguments


# ---------------------------------------------------------------------------------------------
# Meshes


def transform_matrix(transform):
    """softbake's transform: scale, then rotate X, Y, Z about fixed axes, then translate."""
    transform = transform or {}
    scale = transform.get("scale", 1)
    scale = [scale] * 3 if isinstance(scale, (int, float)) else scale
    rotation = Euler([math.radians(a) for a in transform.get("rotate", [0, 0, 0])], "XYZ")
    scaling = Matrix.Diagonal(Vector(scale + [1.0]))
    return Matrix.Translation(transform.get("translate", [0, 0, 0])) @ \
        rotation.to_matrix().to_4x4() @ scaling


def icosphere(mesh_spec):
    """softbake's subdivision s is Blender's s + 1: both have 20 * 4^s faces."""
    subdivisions = mesh_spec.get("subdivisions", 3)
    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=subdivisions + 1,
                               radius=mesh_spec.get("radius", 0.5))
    assert len(bm.faces) == 20 * 4 ** subdivisions
    return bm


def import_file(path):
    """The meshes of an OBJ, PLY or STL file as (mesh name, bmesh in file coordinates)."""
    extension = os.path.splitext(path)[1].lower()
    if extension not in IMPORTERS:
        raise Unsupported(f"{path}: only {', '.join(sorted(IMPORTERS))} files are imported")
    if not os.path.isfile(path):
        raise Unsupported(f"{path}: no such file")
    before = set(bpy.data.objects)
    # Axes as in the file (forward Y, up Z is Blender's own frame): softbake converts nothing.
    if extension == ".obj":
        bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
    elif extension == ".stl":
        bpy.ops.import_mesh.stl(filepath=path, axis_forward="Y", axis_up="Z")
    else:
        bpy.ops.import_mesh.ply(filepath=path)
    meshes = []
    for obj in sorted(set(bpy.data.objects) - before, key=lambda o: o.name):
        if obj.type == "MESH":
            bm = bmesh.new()
            bm.from_mesh(obj.data)
            bm.transform(obj.matrix_world)  # node transforms, as softbake applies them
            meshes.append((obj.data.name, bm))
        bpy.data.objects.remove(obj)
    if not meshes:
        raise Unsupported(f"{path}: no meshes")
    return meshes


def weld_and_triangulate(bm):
    """softbake welds render vertices by position (10^-6 of the mesh's size) and triangulates."""
    size = max((max(v.co[a] for v in bm.verts) - min(v.co[a] for v in bm.verts))
               for a in range(3))
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-6 * size)
    bmesh.ops.triangulate(bm, faces=bm.faces)


def shapes(spec, base_dir):
    """(name suffix, bmesh) pairs for a body's or collider's `mesh` key, before its transform."""
    mesh_spec = spec["mesh"]
    if isinstance(mesh_spec, dict):
        return [("", icosphere(mesh_spec))]
    path = mesh_spec if os.path.isabs(mesh_spec) else os.path.join(base_dir, mesh_spec)
    meshes = import_file(path)
    if len(meshes) > 1 and spec.get("merge_meshes", False):
        merged = bmesh.new()
        for _, bm in meshes:
            scratch = bpy.data.meshes.new("merge")
            bm.to_mesh(scratch)
            merged.from_mesh(scratch)
            bpy.data.meshes.remove(scratch)
        meshes = [("", merged)]
    for _, bm in meshes:
        weld_and_triangulate(bm)
    if len(meshes) == 1:
        return [("", meshes[0][1])]
    return [("/" + name, bm) for name, bm in meshes]


def place(bm, transform):
    """Bakes the transform into the vertices; a mirroring one re-winds the faces as softbake
    does, so the mesh stays outward-facing."""
    matrix = transform_matrix(transform)
    bm.transform(matrix)
    if matrix.determinant() < 0:
        bmesh.ops.reverse_faces(bm, faces=bm.faces)
    bm.normal_update()


def is_closed(bm):
    return all(len(edge.link_faces) == 2 for edge in bm.edges)


def new_object(name, bm):
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


# ---------------------------------------------------------------------------------------------
# softbake material -> Blender cloth settings


def material_values(spec):
    """(stiffness, bend_stiffness, damping, pressure) of a body's `material` key."""
    spec = spec if spec is not None else "rubber"
    if isinstance(spec, str):
        return PRESETS[spec]
    stiffness, bend, damping, pressure = PRESETS[spec.get("preset", "rubber")]
    return (spec.get("stiffness", stiffness), spec.get("bend_stiffness", bend),
            spec.get("damping", damping), spec.get("pressure", pressure))


class Hinge:
    """An interior edge of the rest mesh and the two triangles on it.

    softbake's bending spring joins the wing corners a, b (length d). A fold of the hinge by one
    radian changes d by h_a h_b sin(angle) / d (h: the wings' heights over the edge, angle:
    between the face normals), so its fold stiffness is bend_stiffness * `fold`. Blender's
    angular spring pushes each wing corner with 0.1 * bending_stiffness * edge length per
    radian, a torque of bending_stiffness * `torque`."""

    def __init__(self, fold, torque, height, diagonal):
        self.fold, self.torque, self.height, self.diagonal = fold, torque, height, diagonal


def hinge_geometry(bm):
    """The Hinge of every edge between two triangles."""
    hinges = []
    for edge in bm.edges:
        if len(edge.link_faces) != 2 or any(len(f.verts) != 3 for f in edge.link_faces):
            continue
        p, q = (v.co for v in edge.verts)
        axis = (q - p).normalized()
        wings = [next(v.co for v in f.verts if v not in edge.verts) for f in edge.link_faces]
        heights = [((w - p) - axis * (w - p).dot(axis)).length for w in wings]
        d = (wings[0] - wings[1]).length
        sine = edge.link_faces[0].normal.cross(edge.link_faces[1].normal).length
        if d == 0:
            continue
        height = (heights[0] + heights[1]) / 2
        hinges.append(Hinge(fold=(heights[0] * heights[1] * sine / d) ** 2,
                            torque=0.1 * edge.calc_length() * height, height=height, diagonal=d))
    return hinges


def clamp(value, highest, what, warnings):
    if value > highest:
        warnings.append(f"{what} {value:.4g} clamped to Blender's maximum {highest:g}")
        return highest
    return value


def cloth_settings(material, bm, vertex_mass, fps):
    """Blender ClothSettings values for a softbake material on this rest mesh (see the header
    for the reasoning); all in Blender's units of kg, m and frames (u = 1/fps s)."""
    stiffness, bend, damping, pressure = material
    u2 = 1.0 / (fps * fps)
    warnings = []
    edges = [e.calc_length() for e in bm.edges]
    hinges = hinge_geometry(bm)
    # Under a uniform stretch e the edge springs store k (e L)^2 / 2 and the bending springs
    # bend_stiffness (e d)^2 / 2: the edges alone must carry both (3 bend_stiffness on
    # equilateral triangles, d = sqrt(3) L).
    diagonals = sum(h.diagonal ** 2 for h in hinges) / sum(length ** 2 for length in edges)
    k_eff = (stiffness + bend * diagonals) * u2  # per edge spring, kg / frame^2
    critical = 2 * math.sqrt(k_eff * vertex_mass / 2)  # two masses joined by one spring
    tension = clamp(k_eff * sum(edges) / len(edges), 10000, "tension stiffness", warnings)
    spring_damping = clamp(damping * critical, 50, "spring damping", warnings)

    bending = bend_damping = 0.0
    if hinges:
        bending = bend * u2 * sum(h.fold for h in hinges) / sum(h.torque for h in hinges)
        # Each wing corner feels bending * torque / height^2 per unit of its displacement.
        lever = sum(h.torque / h.height ** 2 for h in hinges) / len(hinges)
        bend_damping = damping * 2 * math.sqrt(bending * lever * vertex_mass)
    values = {
        "tension_stiffness": tension, "tension_stiffness_max": tension,
        "compression_stiffness": tension, "compression_stiffness_max": tension,
        "shear_stiffness": tension, "shear_stiffness_max": tension,  # no shear springs on tris
        "tension_damping": spring_damping, "compression_damping": spring_damping,
        "shear_damping": spring_damping,
        "bending_stiffness": clamp(bending, 10000, "bending stiffness", warnings),
        "bending_damping": clamp(bend_damping, 1000, "bending damping", warnings),
        "pressure_factor": clamp(pressure * u2, 10000, "pressure factor", warnings),
    }
    values["bending_stiffness_max"] = values["bending_stiffness"]
    return values, warnings


# ---------------------------------------------------------------------------------------------
# Scene


def add_collision(obj, friction):
    """A Collision modifier, single sided: what is behind a face is pushed out through it."""
    obj.modifiers.new("Collision", "COLLISION")
    obj.collision.cloth_friction = min(100 * friction, 80)
    obj.collision.thickness_outer = COLLIDER_THICKNESS
    obj.collision.use_normal = True


def inset(bm, skin):
    """Moves a static collider in along its vertex normals, so that bodies kept the collision
    distance away from it rest `skin` away from the collider softbake has."""
    depth = CLOTH_DISTANCE + COLLIDER_THICKNESS - skin
    for vertex in bm.verts:
        vertex.co -= vertex.normal * depth


def add_body(name, bm, body, scene_json, quality):
    """A soft body: cloth with pressure and self-collision, then a Collision modifier so the
    other bodies collide with it."""
    settings = scene_json.get("settings", {})
    fps = settings.get("fps", 24)
    friction = settings.get("collisions", {}).get("friction", DEFAULT_FRICTION)
    closed = is_closed(bm)
    vertex_mass = body.get("mass", 1.0) / len(bm.verts)
    values, warnings = cloth_settings(material_values(body.get("material")), bm, vertex_mass, fps)
    for warning in warnings:
        log(f"{name}: {warning}")
    pin_boxes = body.get("pins", {}).get("boxes", [])

    obj = new_object(name, bm)
    cloth = obj.modifiers.new("Cloth", "CLOTH")
    s = cloth.settings
    s.quality = quality
    s.mass = vertex_mass
    s.air_damping = 0.0
    s.time_scale = 1.0
    for key, value in values.items():
        setattr(s, key, value)
    s.use_pressure = closed
    s.uniform_pressure_force = 1.0
    if pin_boxes:
        s.vertex_group_mass = pin_group(obj, pin_boxes)
    c = cloth.collision_settings
    c.use_collision = True
    c.distance_min = CLOTH_DISTANCE
    c.use_self_collision = body.get("self_collision", True)
    c.self_distance_min = CLOTH_DISTANCE
    c.self_friction = min(100 * friction, 80)
    add_collision(obj, friction)
    return obj, closed


def pin_group(obj, boxes):
    """A vertex group of the vertices inside any pin box (world space, at the start)."""
    group = obj.vertex_groups.new(name="pins")
    inside = [v.index for v in obj.data.vertices
              if any(all(b["min"][a] <= v.co[a] <= b["max"][a] for a in range(3)) for b in boxes)]
    group.add(inside, 1.0, "REPLACE")
    return group.name


def plane(collider, extent):
    """softbake's infinite plane as a square of side `extent` through `point`, facing `normal`."""
    normal = Vector(collider.get("normal", [0, 1, 0])).normalized()
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=extent / 2)
    rotation = Vector((0, 0, 1)).rotation_difference(normal).to_matrix().to_4x4()
    bm.transform(Matrix.Translation(collider.get("point", [0, 0, 0])) @ rotation)
    bm.normal_update()
    return bm


def scene_extent(objects):
    points = [v.co for obj in objects for v in obj.data.vertices]
    return max(max(p[a] for p in points) - min(p[a] for p in points) for a in range(3))


def build_scene(scene_json, base_dir, quality, frames):
    """Creates every body and collider. Returns [(object, closed, rest volume)] of the bodies
    and the total face count. Raises Unsupported naming every body it cannot build."""
    for obj in list(bpy.data.objects):  # the factory startup's cube, camera and light
        bpy.data.objects.remove(obj)
    settings = scene_json.get("settings", {})
    scene = bpy.context.scene
    fps = settings.get("fps", 24)
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    scene.frame_start, scene.frame_end = 1, frames
    gravity = Vector(settings.get("gravity", [0, -9.81, 0]))
    scene.use_gravity = True
    scene.gravity = gravity / (fps * fps * BLENDER_GRAVITY_SCALE)

    problems, bodies, faces = [], [], 0
    for index, body in enumerate(scene_json["bodies"]):
        name = body.get("name", f"body{index}")
        pins = body.get("pins", {})
        if pins.get("indices") or pins.get("particles"):
            problems.append(f"{name}: pins.indices or pins.particles (pin with boxes)")
            continue
        try:
            for suffix, bm in shapes(body, base_dir):
                place(bm, body.get("transform"))
                rest_volume = bm.calc_volume(signed=False)
                faces += len(bm.faces)
                obj, closed = add_body(name + suffix, bm, body, scene_json, quality)
                bodies.append((obj, closed, rest_volume))
        except Unsupported as error:
            problems.append(f"{name}: {error}")
    if problems:
        raise Unsupported("unsupported bodies:\n  " + "\n  ".join(problems))

    skin = settings.get("skin", DEFAULT_SKIN)
    extent = max(20.0, 4 * scene_extent([obj for obj, _, _ in bodies]))
    for index, collider in enumerate(scene_json.get("colliders", [])):
        name = collider.get("name", f"collider{index}")
        if collider["type"] == "plane":
            meshes = [("", plane(collider, extent))]
        else:
            try:
                meshes = shapes(collider, base_dir)
            except Unsupported as error:
                raise Unsupported(f"unsupported collider {name}: {error}") from None
            for _, bm in meshes:
                place(bm, collider.get("transform"))
        for suffix, bm in meshes:
            inset(bm, skin)
            add_collision(new_object(name + suffix, bm), collider.get("friction", DEFAULT_FRICTION))

    for obj, _, _ in bodies:
        cache = obj.modifiers["Cloth"].point_cache
        cache.frame_start, cache.frame_end = 1, frames
    return bodies, faces


# ---------------------------------------------------------------------------------------------
# Run and report


def simulate(frames):
    """Frame 1 initialises the cloth (setup, not timed); frames 2..N are the simulation."""
    scene = bpy.context.scene
    scene.frame_set(1)
    start = time.perf_counter()
    for frame in range(2, frames + 1):
        scene.frame_set(frame)
    return time.perf_counter() - start


def final_state(obj, up, rest_volume):
    """(final / rest volume, centre height, lowest height) of the evaluated body."""
    bm = bmesh.new()
    bm.from_object(obj, bpy.context.evaluated_depsgraph_get())
    heights = [v.co.dot(up) for v in bm.verts]  # objects sit at the origin: local is world
    ratio = bm.calc_volume(signed=False) / rest_volume if rest_volume > 0 else float("nan")
    return ratio, sum(heights) / len(heights), min(heights)


def up_direction(scene_json):
    gravity = Vector(scene_json.get("settings", {}).get("gravity", [0, -9.81, 0]))
    return -gravity.normalized() if gravity.length > 0 else Vector((0, 1, 0))


def main():
    arguments = parse_arguments()
    with open(arguments.scene) as file:
        try:
            scene_json = json.load(file)
        except json.JSONDecodeError as error:
            sys.exit(f"{arguments.scene}: {error} (run it through `softbake scene` first)")
    base_dir = arguments.base_dir or os.path.dirname(os.path.abspath(arguments.scene))
    frames = arguments.frames or scene_json.get("settings", {}).get("frames", 240)
    name = scene_json.get("name", os.path.splitext(os.path.basename(arguments.scene))[0])
    try:
        bodies, faces = build_scene(scene_json, base_dir, arguments.quality, frames)
    except Unsupported as error:
        log(str(error))
        sys.exit(2)

    seconds = simulate(frames)

    up = up_direction(scene_json)
    ratios = []
    for obj, closed, rest_volume in bodies:
        ratio, centre, lowest = final_state(obj, up, rest_volume)
        log(f"{obj.name}: centre_height={centre:.4f} lowest={lowest:.4f} "
            f"volume_ratio={ratio:.4f}{'' if closed else ' (open mesh: no pressure)'}")
        if closed:
            ratios.append(ratio)
    volume_ratio_min = min(ratios) if ratios else float("nan")
    print(f"peer=blender_cloth scene={name} faces={faces} frames={frames} seconds={seconds:.3f} "
          f"frames_per_s={(frames - 1) / seconds:.3f} quality={arguments.quality} "
          f"volume_ratio_min={volume_ratio_min:.4f} threads={bpy.context.scene.render.threads}",
          flush=True)


if __name__ == "__main__":
    try:
        main()
    except SystemExit:
        raise
    except Exception:  # Blender keeps running after a script error; make it an exit status.
        import traceback
        traceback.print_exc()
        sys.exit(1)

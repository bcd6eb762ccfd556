# SPDX-License-Identifier: MIT
"""Creating the Blender data-blocks from a checked BakePlan (reader.plan_bake)."""

import math
import os

import bpy

from .reader import fps_settings, y_up_to_z_up

# The Mesh Cache modifier's Forward/Up axes, measured in Blender 3.4 (a one-point PC2 holding
# (1, 2, 3) evaluated under every pair): +Y/+Z (the default) leaves the data as it is, and
# +Z/-Y turns (x, y, z) into (x, -z, y), Y-up into Blender's Z-up, the same turn the add-on
# applies to the rest mesh and to the volume object. Beware: the pair the OBJ and FBX importers
# use for Y-up files (axis_forward '-Z', axis_up 'Y') gives (x, z, -y) here, upside down: the
# modifier's axes work the other way round.
CACHE_AXES = {
    "z": ("POS_Y", "POS_Z"),
    "y": ("POS_Z", "NEG_Y"),
}


def _blend_path(path, relative):
    """An absolute path, or one relative to the saved .blend file ('//...') when asked for and
    possible (an unsaved file has nothing to be relative to)."""
    path = os.path.abspath(path)
    if relative and bpy.data.is_saved:
        try:
            return bpy.path.relpath(path)
        except ValueError:  # another drive
            return path
    return path


def _material(name, colour):
    mat = bpy.data.materials.new(name)
    mat.diffuse_color = (colour[0], colour[1], colour[2], 1.0)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = (colour[0], colour[1], colour[2], 1.0)
    return mat


def build_mesh(body):
    """A Mesh with the rest mesh's vertices in the file's order, its faces and UVs, in Z-up."""
    rest = body.mesh
    coords = rest.coords
    if body.up == "y":
        y_up_to_z_up(coords)
    me = bpy.data.meshes.new(body.name)
    me.vertices.add(rest.vertex_count)
    me.vertices.foreach_set("co", coords)
    if rest.face_count:
        me.loops.add(len(rest.loop_vertices))
        me.loops.foreach_set("vertex_index", rest.loop_vertices)
        me.polygons.add(rest.face_count)
        me.polygons.foreach_set("loop_start", rest.loop_starts)
        me.polygons.foreach_set("loop_total", rest.loop_totals)
        if rest.loop_uvs is not None:
            uv = me.uv_layers.new(name="UVMap", do_init=False)
            uv.data.foreach_set("uv", rest.loop_uvs)
        # softbake's OBJ frames carry smooth per-vertex normals; shade the same way.
        me.polygons.foreach_set("use_smooth", [True] * rest.face_count)
    me.update(calc_edges=True)
    # validate() never removes or reorders vertices (only bad edges, faces and corners), so the
    # vertex order the point cache relies on is kept.
    me.validate(verbose=False)
    return me


def build_scene(context, plan, relative_paths=True):
    """Creates the collection, the objects and the frame settings. Returns the collection."""
    scene = context.scene
    collection = bpy.data.collections.new(plan.scene)
    scene.collection.children.link(collection)
    collection["softbake_manifest"] = plan.manifest_path
    collection["softbake_units"] = plan.units

    for body in plan.bodies:
        me = build_mesh(body)
        if body.colour is not None:
            me.materials.append(_material(body.name, body.colour))
        obj = bpy.data.objects.new(body.name, me)
        collection.objects.link(obj)
        mod = obj.modifiers.new("softbake " + body.cache.format, 'MESH_CACHE')
        mod.cache_format = body.cache.format
        mod.filepath = _blend_path(body.cache.path, relative_paths)
        # Scene frame F reads the cache's sample (F - frame_start): with frame_start the bake's
        # first frame, scene frame first_frame is sample 0, which is the bake's first frame.
        mod.play_mode = 'SCENE'
        mod.time_mode = 'FRAME'
        mod.frame_start = float(plan.first_frame)
        mod.frame_scale = 1.0
        mod.interpolation = 'LINEAR'  # exact on whole frames; blends between them (motion blur)
        mod.deform_mode = 'OVERWRITE'
        mod.forward_axis, mod.up_axis = CACHE_AXES[body.up]
        mod.flip_axis = set()

    if plan.volume is not None:
        vp = plan.volume
        name = plan.scene + "_vdb"
        vol = bpy.data.volumes.new(name)
        vol.filepath = _blend_path(vp.first_file, relative_paths)
        vol.is_sequence = True
        vol.frame_start = vp.frame_start
        vol.frame_duration = vp.frame_duration
        vol.frame_offset = vp.frame_offset
        # Hold the first and last frames outside the bake, as the Mesh Cache modifier does.
        vol.sequence_mode = 'EXTEND'
        if vp.velocity_grid:
            vol.velocity_grid = vp.velocity_grid
            vol.velocity_unit = 'SECOND'  # softbake's `vel` is in scene units per second
        obj = bpy.data.objects.new(name, vol)
        if vp.up == "y":
            # A volume has no axis setting: turn the object, (x, y, z) -> (x, -z, y).
            obj.rotation_euler = (math.pi / 2.0, 0.0, 0.0)
        collection.objects.link(obj)

    fps, fps_base = fps_settings(plan.fps)
    scene.render.fps = fps
    scene.render.fps_base = fps_base
    # Start first: setting the start pushes the end up when it passes it, and the end is then set.
    scene.frame_start = plan.first_frame
    scene.frame_end = plan.first_frame + plan.frames - 1
    scene.frame_set(plan.first_frame)
    return collection

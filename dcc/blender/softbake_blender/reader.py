# SPDX-License-Identifier: MIT
"""Reading a softbake output folder without Blender: the manifest, the rest meshes (OBJ) and the
point-cache headers (PC2, MDD).

Nothing here imports bpy, so the module runs under any Python 3 (the add-on's checks and tests
use it as it is). Everything is read and checked before the add-on creates a single data-block:
an error leaves the .blend file untouched.
"""

import json
import math
import os
import struct
from array import array


class BakeError(Exception):
    """A problem with the output folder, its message naming the file."""


# --------------------------------------------------------------------------------------------
# Rest mesh


class RestMesh:
    """An OBJ read as it is: vertices in the file's order (never split, merged or reordered),
    polygons as flat index lists, and one UV per face corner when the file has `vt`."""

    __slots__ = ("path", "coords", "loop_vertices", "loop_starts", "loop_totals", "loop_uvs")

    def __init__(self, path):
        self.path = path
        self.coords = array("f")         # x, y, z per vertex
        self.loop_vertices = array("i")  # vertex index per face corner
        self.loop_starts = array("i")    # first corner of each face
        self.loop_totals = array("i")    # corners of each face
        self.loop_uvs = None             # u, v per face corner, or None without `vt`

    @property
    def vertex_count(self):
        return len(self.coords) // 3

    @property
    def face_count(self):
        return len(self.loop_starts)


def _obj_index(token, count, path, line_number, what):
    """An OBJ index (1-based, or negative: relative to the end) as a 0-based index."""
    try:
        i = int(token)
    except ValueError:
        raise BakeError("%s:%d: %s index %r is not an integer" % (path, line_number, what, token))
    if i > 0:
        i -= 1
    elif i < 0:
        i += count
    else:
        raise BakeError("%s:%d: %s index 0 (OBJ indices start at 1)" % (path, line_number, what))
    if not 0 <= i < count:
        raise BakeError("%s:%d: %s index %s is out of range (%d defined)"
                        % (path, line_number, what, token, count))
    return i


def read_obj(path):
    """Reads `v`, `vt` and `f` of an OBJ file; other statements (o, g, s, usemtl, vn, ...) are
    ignored. Raises BakeError naming the file and line on anything malformed."""
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as e:
        raise BakeError("cannot read the rest mesh '%s': %s" % (path, e.strerror or e))
    mesh = RestMesh(path)

    coords = mesh.coords
    uvs = array("f")
    loop_vertices = mesh.loop_vertices
    loop_uv_index = array("i")
    loop_starts = mesh.loop_starts
    loop_totals = mesh.loop_totals
    any_uv = False
    vertex_count = 0
    uv_count = 0

    for line_number, line in enumerate(text.splitlines(), 1):
        if not line or line[0] not in "vf":
            continue
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key == "v":
            if len(parts) < 4:
                raise BakeError("%s:%d: a vertex needs x y z" % (path, line_number))
            try:
                coords.extend((float(parts[1]), float(parts[2]), float(parts[3])))
            except ValueError:
                raise BakeError("%s:%d: a vertex coordinate is not a number" % (path, line_number))
            vertex_count += 1
        elif key == "vt":
            if len(parts) < 3:
                raise BakeError("%s:%d: a texture coordinate needs u v" % (path, line_number))
            try:
                uvs.extend((float(parts[1]), float(parts[2])))
            except ValueError:
                raise BakeError("%s:%d: a texture coordinate is not a number" % (path, line_number))
            uv_count += 1
        elif key == "f":
            corners = parts[1:]
            if len(corners) < 3:
                raise BakeError("%s:%d: a face needs at least 3 corners" % (path, line_number))
            loop_starts.append(len(loop_vertices))
            loop_totals.append(len(corners))
            for corner in corners:
                fields = corner.split("/")
                loop_vertices.append(_obj_index(fields[0], vertex_count, path, line_number, "vertex"))
                if len(fields) > 1 and fields[1]:
                    loop_uv_index.append(_obj_index(fields[1], uv_count, path, line_number,
                                                    "texture coordinate"))
                    any_uv = True
                else:
                    loop_uv_index.append(-1)

    if vertex_count == 0:
        raise BakeError("the rest mesh '%s' has no vertices" % path)
    if any_uv:
        loop_uvs = array("f", bytes(8 * len(loop_uv_index)))
        for corner, t in enumerate(loop_uv_index):
            if t >= 0:
                loop_uvs[2 * corner] = uvs[2 * t]
                loop_uvs[2 * corner + 1] = uvs[2 * t + 1]
        mesh.loop_uvs = loop_uvs
    return mesh


def y_up_to_z_up(coords):
    """(x, y, z) -> (x, -z, y) in place: Y-up data in Blender's Z-up world, the turn the Mesh
    Cache modifier makes with forward +Z and up -Y (build.CACHE_AXES)."""
    for i in range(0, len(coords), 3):
        y = coords[i + 1]
        coords[i + 1] = -coords[i + 2]
        coords[i + 2] = y


# --------------------------------------------------------------------------------------------
# Point caches


class PointCache:
    __slots__ = ("path", "format", "points", "samples", "start", "sample_rate")

    def __init__(self, path, fmt, points, samples, start=None, sample_rate=None):
        self.path = path
        self.format = fmt          # 'PC2' or 'MDD', as the Mesh Cache modifier names them
        self.points = points
        self.samples = samples
        self.start = start         # PC2 only: the header's start frame
        self.sample_rate = sample_rate


def read_pc2_header(path):
    """PC2: little-endian 'POINTCACHE2\\0', int32 version, int32 points, float32 start frame,
    float32 sample rate, int32 samples, then samples x points x 3 float32."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            head = f.read(32)
    except OSError as e:
        raise BakeError("cannot read the point cache '%s': %s" % (path, e.strerror or e))
    if len(head) < 32 or head[:12] != b"POINTCACHE2\0":
        raise BakeError("'%s' is not a PC2 file (no POINTCACHE2 header)" % path)
    version, points, start, rate, samples = struct.unpack("<iiffi", head[12:32])
    if version != 1:
        raise BakeError("'%s': PC2 version %d, expected 1" % (path, version))
    if points <= 0 or samples <= 0:
        raise BakeError("'%s': %d points and %d samples in the PC2 header" % (path, points, samples))
    expected = 32 + 12 * points * samples
    if size != expected:
        raise BakeError("'%s' is %d bytes, but its header (%d points, %d samples) needs %d"
                        % (path, size, points, samples, expected))
    return PointCache(path, "PC2", points, samples, start, rate)


def read_mdd_header(path):
    """MDD: big-endian int32 frames, int32 points, frames x float32 time, then frames x points x 3
    float32."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError as e:
        raise BakeError("cannot read the point cache '%s': %s" % (path, e.strerror or e))
    if len(head) < 8:
        raise BakeError("'%s' is too short for an MDD file" % path)
    frames, points = struct.unpack(">ii", head)
    if points <= 0 or frames <= 0:
        raise BakeError("'%s': %d frames and %d points in the MDD header" % (path, frames, points))
    expected = 8 + 4 * frames + 12 * points * frames
    if size != expected:
        raise BakeError("'%s' is %d bytes, but its header (%d frames, %d points) needs %d"
                        % (path, size, frames, points, expected))
    return PointCache(path, "MDD", points, frames)


# --------------------------------------------------------------------------------------------
# Materials (optional: the colours the PNG frames use)


def read_mtl_colours(path):
    """{material name: (r, g, b)} from the `Kd` lines of an MTL file; {} when it is unreadable."""
    colours = {}
    try:
        with open(path, "r", encoding="utf-8", errors="replace") as f:
            name = None
            for line in f:
                parts = line.split()
                if len(parts) >= 2 and parts[0] == "newmtl":
                    name = line.strip()[len("newmtl"):].strip()
                elif len(parts) >= 4 and parts[0] == "Kd" and name is not None:
                    colours[name] = tuple(float(x) for x in parts[1:4])
    except (OSError, ValueError):
        return {}
    return colours


# --------------------------------------------------------------------------------------------
# The whole bake


class BodyPlan:
    __slots__ = ("name", "mesh", "cache", "up", "colour")

    def __init__(self, name, mesh, cache, up, colour):
        self.name = name
        self.mesh = mesh      # RestMesh, coordinates as in the file (in `up`)
        self.cache = cache    # PointCache
        self.up = up          # 'y' or 'z'
        self.colour = colour  # (r, g, b) or None


class VolumePlan:
    __slots__ = ("first_file", "frame_start", "frame_duration", "frame_offset", "up",
                 "velocity_grid")

    def __init__(self, first_file, frame_start, frame_duration, frame_offset, up, velocity_grid):
        self.first_file = first_file
        self.frame_start = frame_start
        self.frame_duration = frame_duration
        self.frame_offset = frame_offset
        self.up = up
        self.velocity_grid = velocity_grid


class BakePlan:
    def __init__(self):
        self.manifest_path = ""
        self.folder = ""
        self.scene = ""
        self.fps = 24.0
        self.frames = 0
        self.first_frame = 1
        self.units = "m"
        self.bodies = []     # BodyPlan
        self.volume = None   # VolumePlan or None
        self.warnings = []


def fps_settings(fps):
    """(render.fps, render.fps_base) for a frame rate: Blender's frame rate is fps / fps_base with
    an integer fps. 24 -> (24, 1); otherwise (ceil(fps), ceil(fps) / fps), so 24000/1001 gives
    Blender's own NTSC setting (24, 1.001) and 23.976 gives (24, 1.001001...), 23.976 exactly."""
    if not (fps > 0 and math.isfinite(fps)):
        raise ValueError("fps %r is not a positive number" % (fps,))
    whole = round(fps)
    if whole >= 1 and abs(fps - whole) <= 1e-9 * fps:
        return int(whole), 1.0
    base_fps = max(1, math.ceil(fps))
    return int(base_fps), base_fps / fps


def _up_axis(value, where):
    up = (value or "y").lower()
    if up not in ("y", "z"):
        raise BakeError("%s: up axis %r, expected 'y' or 'z'" % (where, value))
    return up


def _resolve(folder, relative, what, manifest_path):
    if not isinstance(relative, str) or not relative:
        raise BakeError("'%s': %s has no file name" % (manifest_path, what))
    path = os.path.normpath(os.path.join(folder, relative))
    if not os.path.isfile(path):
        raise BakeError("%s '%s' (listed in '%s') does not exist" % (what, path, manifest_path))
    return path


def manifest_path_of(path):
    """The manifest for what the user picked: the file itself, or manifest.json in a folder."""
    path = os.path.abspath(os.path.expanduser(path))
    if os.path.isdir(path):
        path = os.path.join(path, "manifest.json")
    return path


def plan_bake(path, use_mdd=False):
    """Reads and checks everything the import needs. Raises BakeError naming the file."""
    manifest_path = manifest_path_of(path)
    if not os.path.isfile(manifest_path):
        raise BakeError("no softbake manifest at '%s'" % manifest_path)
    try:
        with open(manifest_path, "r", encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, UnicodeDecodeError) as e:
        raise BakeError("cannot read the manifest '%s': %s" % (manifest_path, e))
    except json.JSONDecodeError as e:
        raise BakeError("the manifest '%s' is not valid JSON: %s" % (manifest_path, e))
    if not isinstance(manifest, dict) or "frames" not in manifest or "scene" not in manifest:
        raise BakeError("'%s' is not a softbake manifest (no scene and frames)" % manifest_path)

    plan = BakePlan()
    plan.manifest_path = manifest_path
    plan.folder = folder = os.path.dirname(manifest_path)
    plan.scene = str(manifest.get("scene") or "softbake")
    try:
        plan.frames = int(manifest["frames"])
        plan.first_frame = int(manifest.get("first_frame", 1))
        plan.fps = float(manifest.get("fps", 24.0))
        fps_settings(plan.fps)
    except (TypeError, ValueError) as e:
        raise BakeError("'%s': bad frames, first_frame or fps: %s" % (manifest_path, e))
    if plan.frames < 1:
        raise BakeError("'%s': the bake has %d frames" % (manifest_path, plan.frames))
    plan.units = str(manifest.get("units") or "m")

    status = manifest.get("status", "complete")
    if status != "complete":
        plan.warnings.append("'%s': status '%s' (%s): the run did not finish"
                             % (manifest_path, status, manifest.get("reason", "no reason given")))

    particles = {}
    for body in manifest.get("bodies") or []:
        if isinstance(body, dict) and "name" in body:
            particles[body["name"]] = body.get("particles")

    run_options = (manifest.get("run") or {}).get("options") or {}
    sequences = [s for s in manifest.get("sequences") or [] if isinstance(s, dict)]

    colours = {}
    for seq in sequences:
        if seq.get("format") == "obj":
            for extra in seq.get("files") or []:
                if isinstance(extra, str) and extra.endswith(".mtl"):
                    colours.update(read_mtl_colours(os.path.join(folder, extra)))

    for entry in manifest.get("point_caches") or []:
        if not isinstance(entry, dict):
            continue
        name = str(entry.get("body") or "body")
        up = _up_axis(entry.get("up"), "'%s', body '%s'" % (manifest_path, name))
        mesh_path = _resolve(folder, entry.get("mesh"), "the rest mesh of body '%s'" % name,
                             manifest_path)
        pc2, mdd = entry.get("pc2"), entry.get("mdd")
        if mdd and (use_mdd or not pc2):
            cache_path = _resolve(folder, mdd, "the MDD point cache of body '%s'" % name,
                                  manifest_path)
            cache = read_mdd_header(cache_path)
        elif pc2:
            cache_path = _resolve(folder, pc2, "the PC2 point cache of body '%s'" % name,
                                  manifest_path)
            cache = read_pc2_header(cache_path)
        else:
            raise BakeError("'%s': body '%s' has neither a PC2 nor an MDD point cache"
                            % (manifest_path, name))
        mesh = read_obj(mesh_path)
        if cache.points != mesh.vertex_count:
            raise BakeError("the point cache '%s' has %d points but its rest mesh '%s' has %d "
                            "vertices" % (cache.path, cache.points, mesh_path, mesh.vertex_count))
        expected = particles.get(name)
        if isinstance(expected, int) and expected != mesh.vertex_count:
            raise BakeError("the rest mesh '%s' has %d vertices, but the manifest gives body '%s' "
                            "%d particles" % (mesh_path, mesh.vertex_count, name, expected))
        if cache.samples != plan.frames:
            plan.warnings.append("'%s' holds %d frames, the manifest %d: frames past its last "
                                 "hold the last" % (cache.path, cache.samples, plan.frames))
        plan.bodies.append(BodyPlan(name, mesh, cache, up, colours.get(name)))

    for seq in sequences:
        if seq.get("format") != "vdb":
            continue
        printf = seq.get("printf_pattern")
        if not isinstance(printf, str) or "%" not in printf:
            raise BakeError("'%s': the VDB sequence has no printf_pattern" % manifest_path)
        try:
            first = printf % plan.first_frame
        except (TypeError, ValueError):
            raise BakeError("'%s': bad VDB printf_pattern %r" % (manifest_path, printf))
        first_file = _resolve(folder, first, "the first VDB frame", manifest_path)
        last = os.path.join(folder, printf % (plan.first_frame + plan.frames - 1))
        if not os.path.isfile(last):
            plan.warnings.append("the last VDB frame '%s' does not exist" % os.path.normpath(last))
        up = _up_axis(run_options.get("up") or (manifest.get("point_caches") or [{}])[0].get("up"),
                      manifest_path)
        # Blender's volume sequences number their files from the path's own frame number:
        # file = scene frame - frame_start + 1 + frame_offset, so frame_start is the first frame
        # and frame_offset shifts to the number the first file carries.
        velocity = "vel" if len(particles) == 1 else ""
        plan.volume = VolumePlan(first_file, plan.first_frame, plan.frames,
                                 plan.first_frame - 1, up, velocity)
        break

    if not plan.bodies and plan.volume is None:
        raise BakeError("'%s' lists no point cache and no VDB sequence: bake with --pc2 (or "
                        "--mdd) and/or --vdb" % manifest_path)
    if not plan.bodies:
        plan.warnings.append("'%s' lists no point caches (bake with --pc2 or --mdd): only the "
                             "VDB volume is imported" % manifest_path)
    return plan

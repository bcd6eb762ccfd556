# SPDX-License-Identifier: MIT
"""softbake bake importer for Blender.

File > Import > softbake bake (.json manifest): reads a softbake output folder's manifest.json
and creates, in a new collection named after the scene, one mesh object per body (its rest mesh,
with a Mesh Cache modifier playing its PC2 or MDD point cache), a Volume object on the VDB
sequence when there is one, and sets the scene's frame range and frame rate.

Scripted (headless) use:

    blender -b --factory-startup --python-expr "import bpy; \
        bpy.ops.preferences.addon_install(filepath='softbake_blender.zip'); \
        bpy.ops.preferences.addon_enable(module='softbake_blender'); \
        bpy.ops.import_scene.softbake(filepath='/path/to/out/manifest.json')"
"""

bl_info = {
    "name": "softbake bake importer",
    "author": "softbake",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > softbake bake (.json manifest)",
    "description": "Import a softbake output folder: bodies with their PC2/MDD point caches "
                   "(Mesh Cache modifier), the VDB sequence, the frame range and fps",
    "category": "Import-Export",
}

if "bpy" in locals():  # reloading the add-on (F3 > Reload Scripts)
    import importlib
    if "reader" in locals():
        importlib.reload(reader)  # noqa: F821
    if "build" in locals():
        importlib.reload(build)  # noqa: F821

import time

import bpy
from bpy.props import BoolProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import build, reader


class IMPORT_SCENE_OT_softbake(bpy.types.Operator, ImportHelper):
    """Import a softbake bake: the bodies with their point caches, the VDB sequence, the frame
    range and frame rate, from the output folder's manifest.json"""

    bl_idname = "import_scene.softbake"
    bl_label = "Import softbake bake"
    bl_options = {'REGISTER', 'UNDO'}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={'HIDDEN'})

    use_mdd: BoolProperty(
        name="Prefer MDD",
        description="Play the MDD point caches where a body has both PC2 and MDD "
                    "(by default PC2; MDD is used where a body has no PC2)",
        default=False,
    )
    use_relative_paths: BoolProperty(
        name="Relative Paths",
        description="Store the cache and VDB paths relative to the .blend file "
                    "(when it has been saved)",
        default=True,
    )

    def execute(self, context):
        start = time.perf_counter()
        try:
            plan = reader.plan_bake(self.filepath, use_mdd=self.use_mdd)
        except reader.BakeError as e:
            self.report({'ERROR'}, str(e))
            return {'CANCELLED'}
        for warning in plan.warnings:
            self.report({'WARNING'}, warning)
        try:
            collection = build.build_scene(context, plan, self.use_relative_paths)
        except (RuntimeError, TypeError, ValueError) as e:
            self.report({'ERROR'}, "importing '%s' failed: %s" % (plan.manifest_path, e))
            return {'CANCELLED'}
        self.report({'INFO'}, "softbake: imported '%s' (%d bodies%s, frames %d-%d at %g fps) "
                    "into collection '%s' in %.2f s"
                    % (plan.manifest_path, len(plan.bodies),
                       ", VDB volume" if plan.volume else "", plan.first_frame,
                       plan.first_frame + plan.frames - 1, plan.fps, collection.name,
                       time.perf_counter() - start))
        return {'FINISHED'}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "use_mdd")
        layout.prop(self, "use_relative_paths")


def menu_func_import(self, context):
    self.layout.operator(IMPORT_SCENE_OT_softbake.bl_idname, text="softbake bake (.json manifest)")


def register():
    bpy.utils.register_class(IMPORT_SCENE_OT_softbake)
    bpy.types.TOPBAR_MT_file_import.append(menu_func_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_func_import)
    bpy.utils.unregister_class(IMPORT_SCENE_OT_softbake)


if __name__ == "__main__":
    register()

"""Submesh tools: select linked submeshes, select linked across, deduplicate, merge by distance
per submesh, pack UVs by Z. Thin operators over the jobs in boxmarch.tool_jobs (which the command
line runs too): each operator's properties become the tool's options.

Each works in Edit Mode on every object in (multi-object) Edit Mode, and in Object Mode on the
selected mesh objects (whole meshes for dedup, merge and pack; the stored selection for the two
select tools). Bad input cancels with a message before anything is changed."""
from __future__ import annotations

import dataclasses
import time

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty

from .. import mesh_io, tool_jobs


class _SubmeshTool:
    bl_options = {"REGISTER", "UNDO"}
    tool = None  # the tool_jobs class this operator runs; its fields are the operator's properties

    @classmethod
    def poll(cls, context):
        return context.mode in {"OBJECT", "EDIT_MESH"}

    def execute(self, context):
        in_mode = context.objects_in_mode_unique_data if context.mode == "EDIT_MESH" else context.selected_objects
        objects = mesh_io.one_object_per_mesh(in_mode)
        if not objects:
            self.report({"ERROR"}, "Select at least one mesh object")
            return {"CANCELLED"}
        options = {option.name: getattr(self, option.name) for option in dataclasses.fields(self.tool)}
        start = time.perf_counter()
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            message = tool_jobs.run_tool(context, self.tool(**options), objects, wm.progress_update)
        except (tool_jobs.ToolInputError, ValueError) as error:
            self.report({"ERROR"}, f"Nothing changed: {error}")
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        self.report({"INFO"}, f"{message} ({time.perf_counter() - start:.2f} s)")
        return {"FINISHED"}


class BOXMARCH_OT_select_linked_submeshes(_SubmeshTool, bpy.types.Operator):
    """Select every submesh that has at least one selected vertex, whole (Ctrl+L for all of them at once)"""

    bl_idname = "boxmarch.select_linked_submeshes"
    bl_label = "Select Linked Submeshes"
    tool = tool_jobs.SelectLinked


class BOXMARCH_OT_select_linked_across(_SubmeshTool, bpy.types.Operator):
    """Select linked submeshes, also across to other submeshes with a vertex within Epsilon of a reached vertex"""

    bl_idname = "boxmarch.select_linked_across"
    bl_label = "Select Linked Across Submeshes"
    tool = tool_jobs.SelectLinkedAcross

    epsilon: FloatProperty(name="Epsilon", default=tool_jobs.SelectLinkedAcross.epsilon, soft_min=0.0, soft_max=1.0,
                           precision=6, subtype="DISTANCE",
                           description="Vertices of different submeshes this close (true distance) link them")


class BOXMARCH_OT_dedup_submeshes(_SubmeshTool, bpy.types.Operator):
    """Delete selected submeshes that duplicate another selected submesh within Tolerance (the lowest vertex index stays)"""

    bl_idname = "boxmarch.dedup_submeshes"
    bl_label = "Delete Duplicate Submeshes"
    tool = tool_jobs.DeleteDuplicates

    tolerance: FloatProperty(name="Tolerance", default=tool_jobs.DeleteDuplicates.tolerance, soft_min=0.0,
                             soft_max=1.0, precision=6, subtype="DISTANCE",
                             description="Every vertex must lie this close to a distinct vertex of the kept copy")


class BOXMARCH_OT_merge_by_distance_submeshes(_SubmeshTool, bpy.types.Operator):
    """Merge vertices closer than Distance inside each selected submesh, never across submeshes (Blender's Merge by Distance per submesh)"""

    bl_idname = "boxmarch.merge_by_distance_submeshes"
    bl_label = "Merge by Distance per Submesh"
    tool = tool_jobs.MergeByDistance

    distance: FloatProperty(name="Merge Distance", default=tool_jobs.MergeByDistance.distance, soft_min=0.0, soft_max=1.0, precision=6,
                            subtype="DISTANCE", description="Vertices of one submesh this close merge")


class BOXMARCH_OT_pack_uv_by_z(_SubmeshTool, bpy.types.Operator):
    """Pack the UV islands of the selected faces in rows sorted by the Z height of their submesh (highest on top)"""

    bl_idname = "boxmarch.pack_uv_by_z"
    bl_label = "Pack UV Islands by Z"
    tool = tool_jobs.PackUvByZ

    padding: FloatProperty(name="Padding", default=tool_jobs.PackUvByZ.padding, min=0.0, max=0.49, precision=4,
                           description="UV space between islands and around the square")
    max_per_row: IntProperty(name="Max per Row", default=0, min=0,
                             description="Most islands in one row (0: as many as fit)")
    lock_overlapping: BoolProperty(name="Lock Overlapping", default=False,
                                   description="Islands whose UV bounds overlap move together")
    uv_map: StringProperty(name="UV Map", default="",
                           description="UV map to pack (empty: each mesh's active UV map)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        for name in ("padding", "max_per_row", "lock_overlapping"):
            layout.prop(self, name)
        ob = context.active_object
        if ob is not None and ob.type == "MESH":
            layout.prop_search(self, "uv_map", ob.data, "uv_layers")
        else:
            layout.prop(self, "uv_map")


def menu_select(self, _context):
    layout = self.layout
    layout.separator()
    layout.operator(BOXMARCH_OT_select_linked_submeshes.bl_idname)
    layout.operator(BOXMARCH_OT_select_linked_across.bl_idname)


def menu_clean(self, _context):
    layout = self.layout
    layout.separator()
    layout.operator(BOXMARCH_OT_dedup_submeshes.bl_idname)
    layout.operator(BOXMARCH_OT_merge_by_distance_submeshes.bl_idname)


def menu_uv(self, _context):
    self.layout.separator()
    self.layout.operator(BOXMARCH_OT_pack_uv_by_z.bl_idname)


classes = (BOXMARCH_OT_select_linked_submeshes, BOXMARCH_OT_select_linked_across, BOXMARCH_OT_dedup_submeshes,
           BOXMARCH_OT_merge_by_distance_submeshes, BOXMARCH_OT_pack_uv_by_z)
menus = (("VIEW3D_MT_select_edit_mesh", menu_select), ("VIEW3D_MT_edit_mesh_clean", menu_clean),
         ("VIEW3D_MT_uv_map", menu_uv))

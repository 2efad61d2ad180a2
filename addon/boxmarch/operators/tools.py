"""Submesh tools: select linked submeshes, select linked across, deduplicate, merge by distance
per submesh, pack UVs by Z. Thin shells over boxmarch.mesh_edit and boxmarch.core.

Each works in Edit Mode on every object in (multi-object) Edit Mode, and in Object Mode on the
selected mesh objects (whole meshes for dedup, merge and pack; the stored selection for the two
select tools). Bad input cancels with a message before anything is changed."""
from __future__ import annotations

import time

import bpy
import numpy as np
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty

from .. import core, mesh_edit


class _SubmeshTool:
    bl_options = {"REGISTER", "UNDO"}
    need_faces = False
    needs_vertex_selection = True  # in Edit Mode, the selection says which submeshes to work on

    @classmethod
    def poll(cls, context):
        return context.mode in {"OBJECT", "EDIT_MESH"}

    def execute(self, context):
        objects = mesh_edit.tool_objects(context)
        if not objects:
            self.report({"ERROR"}, "Select at least one mesh object")
            return {"CANCELLED"}
        start = time.perf_counter()
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            with mesh_edit.object_mode(context) as edit:
                try:
                    # Read and check every mesh before changing any.
                    arrays = [mesh_edit.read_mesh(ob.data, self.need_faces) for ob in objects]
                    if edit and self.needs_vertex_selection and not any(
                            mesh_edit.read_vertex_selection(ob.data).any() for ob in objects):
                        raise mesh_edit.ToolInputError("no vertex is selected")
                    wm.progress_update(20)
                    outcome = self.run(context, objects, arrays, edit, wm)
                except (mesh_edit.ToolInputError, ValueError) as error:
                    self.report({"ERROR"}, f"Nothing changed: {error}")
                    return {"CANCELLED"}
            # Geometry edits that finish inside Edit Mode run once the objects are back there.
            message = outcome() if callable(outcome) else outcome
        finally:
            wm.progress_end()
        self.report({"INFO"}, f"{message} ({time.perf_counter() - start:.2f} s)")
        return {"FINISHED"}

    @staticmethod
    def chosen_submeshes(ob, arrays, edit):
        """uint8 per submesh: touched by the vertex selection in Edit Mode, all in Object Mode."""
        if not edit:
            return np.ones(arrays.submesh_count, np.uint8)
        selected = mesh_edit.read_vertex_selection(ob.data)
        chosen = np.zeros(arrays.submesh_count, np.uint8)
        chosen[arrays.submesh_of_vertex[selected]] = 1
        return chosen


def _grow_selection(objects, arrays, grow) -> int:
    """Replace each mesh's visible vertex selection by what grow(selected, arrays) returns as
    (mask, submeshes selected); hidden vertices stay unselected. Returns the submeshes selected."""
    total = 0
    for ob, a in zip(objects, arrays):
        hidden = mesh_edit.hidden_vertices(ob.data)
        selected = mesh_edit.read_vertex_selection(ob.data) & ~hidden
        mask, count = grow(selected, a)
        mesh_edit.write_selection(ob.data, a, mask.astype(bool) & ~hidden)
        total += count
    return total


class BOXMARCH_OT_select_linked_submeshes(_SubmeshTool, bpy.types.Operator):
    """Select every submesh that has at least one selected vertex, whole (Ctrl+L for all of them at once)"""

    bl_idname = "boxmarch.select_linked_submeshes"
    bl_label = "Select Linked Submeshes"

    def run(self, context, objects, arrays, edit, wm):
        total = _grow_selection(objects, arrays, lambda selected, a: core.select_linked_submeshes(
            selected, a.submesh_of_vertex, a.submesh_count))
        return f"Selected {total} submesh(es) in {len(objects)} mesh(es)"


class BOXMARCH_OT_select_linked_across(_SubmeshTool, bpy.types.Operator):
    """Select linked submeshes, also across to other submeshes with a vertex within Epsilon of a reached vertex"""

    bl_idname = "boxmarch.select_linked_across"
    bl_label = "Select Linked Across Submeshes"

    epsilon: FloatProperty(name="Epsilon", default=1e-4, soft_min=0.0, soft_max=1.0, precision=6, subtype="DISTANCE",
                           description="Vertices of different submeshes this close (true distance) link them")

    def run(self, context, objects, arrays, edit, wm):
        total = _grow_selection(objects, arrays, lambda selected, a: core.select_linked_across(
            a.positions, selected, a.submesh_of_vertex, a.submesh_count, self.epsilon))
        return f"Selected {total} submesh(es) in {len(objects)} mesh(es), epsilon {self.epsilon:g}"


class BOXMARCH_OT_dedup_submeshes(_SubmeshTool, bpy.types.Operator):
    """Delete selected submeshes that duplicate another selected submesh within Tolerance (the lowest vertex index stays)"""

    bl_idname = "boxmarch.dedup_submeshes"
    bl_label = "Delete Duplicate Submeshes"

    tolerance: FloatProperty(name="Tolerance", default=1e-4, soft_min=0.0, soft_max=1.0, precision=6, subtype="DISTANCE",
                             description="Every vertex must lie this close to a distinct vertex of the kept copy")

    def run(self, context, objects, arrays, edit, wm):
        plans, total = [], 0
        for ob, a in zip(objects, arrays):
            duplicate_of, count = core.find_duplicate_submeshes(
                a.positions, a.submesh_of_vertex, a.submesh_count, self.chosen_submeshes(ob, a, edit), self.tolerance)
            plans.append((ob, a, (duplicate_of >= 0)[a.submesh_of_vertex], mesh_edit.read_vertex_selection(ob.data)))
            total += count
        wm.progress_update(50)
        message = f"Deleted {total} duplicate submesh(es) in {len(objects)} mesh(es), tolerance {self.tolerance:g}"
        if not total:
            return message
        if all(mesh_edit.can_rebuild(ob.data) for ob in objects):
            # Whole submeshes go: the survivors' rows, rebuilt in one go with every attribute
            # (the selection included) carried over.
            for ob, a, delete, _selection in plans:
                if delete.any():
                    removed = core.remove_vertices(*a.topology, delete, mesh_edit.read_corner_edges(ob.data))
                    mesh_edit.rebuild_welded(ob.data, a.positions, removed)
            return message
        action = mesh_edit.delete_vertices(context, plans, edit)
        return message if action is None else lambda: (action(), message)[1]


class BOXMARCH_OT_merge_by_distance_submeshes(_SubmeshTool, bpy.types.Operator):
    """Merge vertices closer than Distance inside each selected submesh, never across submeshes (Blender's Merge by Distance per submesh)"""

    bl_idname = "boxmarch.merge_by_distance_submeshes"
    bl_label = "Merge by Distance per Submesh"

    distance: FloatProperty(name="Merge Distance", default=1e-3, soft_min=0.0, soft_max=1.0, precision=6,
                            subtype="DISTANCE", description="Vertices of one submesh this close merge")

    def run(self, context, objects, arrays, edit, wm):
        # The merge computed here and written as a rebuilt mesh (fast, Blender 4.1+), or
        # Blender's own Merge by Distance on a planned selection where a rebuild could lose
        # data or Blender's weld would do more (split or dedupe faces).
        chosen = [self.chosen_submeshes(ob, a, edit) for ob, a in zip(objects, arrays)]
        welds = []
        for ob, a, c in zip(objects, arrays, chosen):
            target, merged_positions, count = core.merge_targets(a.positions, a.submesh_of_vertex, a.submesh_count,
                                                                 c, self.distance)
            weld = None
            if count and mesh_edit.can_rebuild(ob.data):
                weld = core.weld(*a.topology, target, mesh_edit.read_corner_edges(ob.data))
            if count and (weld is None or weld["needs_blender"]):
                welds = None
                break
            welds.append((ob, merged_positions, weld, count))
        wm.progress_update(50)
        if welds is not None:
            removed = 0
            for ob, merged_positions, weld, count in welds:
                if count:
                    mesh_edit.rebuild_welded(ob.data, merged_positions, weld)
                    removed += count
            return f"Removed {removed} vertices in {len(objects)} mesh(es), distance {self.distance:g}"

        plans, passes = [], 0
        for ob, a, c in zip(objects, arrays, chosen):
            pass_of_vertex, count = core.merge_passes(a.positions, a.submesh_of_vertex, a.submesh_count, c,
                                                      self.distance)
            plans.append((ob, a, pass_of_vertex, mesh_edit.read_vertex_selection(ob.data)))
            passes = max(passes, count)
        if not passes:
            return "Removed 0 vertices: no submesh has vertices that close"
        before = sum(len(a.positions) for a in arrays)
        action = mesh_edit.merge_by_distance(context, plans, self.distance, edit,
                                             lambda k, n: wm.progress_update(50 + 50 * k // n))

        def finish():
            if action is not None:
                action()
            removed = before - mesh_edit.vertex_total(objects)
            return (f"Removed {removed} vertices in {len(objects)} mesh(es) with Blender's merge "
                    f"({passes} pass(es)), distance {self.distance:g}")
        return finish


class BOXMARCH_OT_pack_uv_by_z(_SubmeshTool, bpy.types.Operator):
    """Pack the UV islands of the selected faces in rows sorted by the Z height of their submesh (highest on top)"""

    bl_idname = "boxmarch.pack_uv_by_z"
    bl_label = "Pack UV Islands by Z"
    need_faces = True
    needs_vertex_selection = False  # faces decide, and the core says when none is selected

    padding: FloatProperty(name="Padding", default=0.002, min=0.0, max=0.49, precision=4,
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

    def run(self, context, objects, arrays, edit, wm):
        # All meshes pack together into one square, as Blender packs multi-object UVs.
        names = [mesh_edit.uv_map_name(ob.data, self.uv_map) for ob in objects]
        parts = {key: [] for key in ("positions", "edges", "face_starts", "face_sizes", "corner_verts",
                                     "ids", "heights", "uv", "mask")}
        vertices = corners = submeshes = 0
        for ob, a, name in zip(objects, arrays, names):
            parts["positions"].append(a.positions)
            parts["edges"].append(a.edges + vertices)
            parts["face_starts"].append(a.face_starts + corners)
            parts["face_sizes"].append(a.face_sizes)
            parts["corner_verts"].append(a.corner_verts + vertices)
            parts["ids"].append(a.submesh_of_vertex + submeshes)
            parts["heights"].append(mesh_edit.world_heights(ob, a.positions))
            parts["uv"].append(mesh_edit.read_uv(ob.data, name))
            parts["mask"].append(mesh_edit.read_face_selection(ob.data) if edit
                                 else np.ones(len(a.face_starts), bool))
            vertices += len(a.positions)
            corners += len(a.corner_verts)
            submeshes += a.submesh_count
        joined = {key: np.concatenate(value) for key, value in parts.items()}
        if not joined["mask"].any():
            raise mesh_edit.ToolInputError("no face is selected")
        uv = np.ascontiguousarray(joined["uv"])
        report = core.pack_uv_by_height(
            uv, joined["positions"], joined["edges"].astype(np.int32), joined["face_starts"].astype(np.int32),
            joined["face_sizes"], joined["corner_verts"].astype(np.int32), vertex_height=joined["heights"],
            submesh_of_vertex=joined["ids"].astype(np.int32), submesh_count=submeshes, face_mask=joined["mask"],
            padding=self.padding, max_per_row=self.max_per_row, lock_overlapping=self.lock_overlapping)
        wm.progress_update(80)
        offset = 0
        for ob, a, name in zip(objects, arrays, names):
            mesh_edit.write_uv(ob.data, name, uv[offset:offset + len(a.corner_verts)])
            offset += len(a.corner_verts)
        return (f"Packed {report['islands']} UV islands ({report['groups']} units, {report['rows']} rows) "
                f"by Z at scale {report['scale']:.4g}")


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

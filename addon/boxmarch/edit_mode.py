"""Edit Mode beside mesh_io: leaving and re-entering it, object selection, and Blender's own
edit-mode operators (``mesh.delete``, ``mesh.remove_doubles``) run on a selection the core planned,
for the cases where rebuilding a mesh from arrays could lose data (vertex groups, shape keys,
Blender before 4.1) or Blender's weld would do more than the core's (split or dedupe faces).

The planned selections ride in boolean vertex attributes, which survive the geometry changes
(a merged vertex keeps its target's values)."""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable

import bpy
import numpy as np

from . import mesh_io

MERGE_PASS_ATTRIBUTE = "boxmarch_merge_pass"
SAVED_SELECTION_ATTRIBUTE = "boxmarch_saved_selection"

# Blender 4.2+ selects by a boolean attribute inside Edit Mode: the tools then change geometry and
# restore the selection in one Edit Mode session (leaving and re-entering Edit Mode on a million
# vertices costs most of a second). Older versions take a round trip through Object Mode.
SELECT_BY_ATTRIBUTE = bpy.app.version >= (4, 2, 0)


@contextmanager
def object_mode(context):
    """Leave Edit Mode (Blender writes the edit mesh back) for the body, return afterwards.
    Yields True when the body runs for an operator called in Edit Mode."""
    edit = context.mode == "EDIT_MESH"
    if edit:
        bpy.ops.object.mode_set(mode="OBJECT")
    try:
        yield edit
    finally:
        if edit:
            bpy.ops.object.mode_set(mode="EDIT")


def select_only(view_layer, objects) -> None:
    """Select exactly ``objects`` in the view layer and make the first active."""
    # The selected ones, not every object: the view layer's list syncs with the scene lazily (an
    # object just linked is missing from it, one just removed shows as None).
    for ob in list(view_layer.objects.selected):
        if ob is not None:
            ob.select_set(False)
    for ob in objects:
        ob.select_set(True)
    view_layer.objects.active = objects[0] if objects else None


def in_edit_mode(context, objects, action: Callable[[], None]) -> None:
    """Run ``action`` with exactly ``objects`` in Edit Mode, from and back to Object Mode; the
    object selection and the active object are restored afterwards."""
    view_layer = context.view_layer
    previous_active = view_layer.objects.active
    previous_selected = list(context.selected_objects)
    select_only(view_layer, objects)
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        action()
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
        select_only(view_layer, previous_selected)
        view_layer.objects.active = previous_active


def _select_by_attribute(objects, name) -> None:
    """Edit Mode: select exactly the vertices whose boolean attribute ``name`` is set."""
    bpy.ops.mesh.select_all(action="DESELECT")
    active = {}
    for ob in objects:
        attributes = ob.data.attributes
        active[ob.name] = attributes.active.name if attributes.active is not None else None
        attributes.active = attributes[name]
    bpy.ops.mesh.select_by_attribute()
    for ob in objects:
        previous = active[ob.name]
        if previous is not None and previous in ob.data.attributes:
            ob.data.attributes.active = ob.data.attributes[previous]


@dataclass
class BlenderEdit:
    """Blender's edit-mode operators still to run on ``objects`` once the calling operator is in
    Edit Mode again (or, from Object Mode, in an Edit Mode session of their own)."""

    objects: list
    action: Callable[[], None]

    def run(self, context, edit: bool) -> None:
        if edit:
            self.action()
        else:
            in_edit_mode(context, self.objects, self.action)


@dataclass
class VertexPlan:
    """One mesh's share of a planned edit: ``values`` per vertex (a delete mask, or a merge pass
    with -1 for no merge), and the user's vertex selection to restore afterwards."""

    ob: object
    values: np.ndarray
    selection: np.ndarray


def _reselect(mesh, selection) -> None:
    edges, face_starts, _sizes, corner_verts = mesh_io.read_topology(mesh)
    mesh_io.write_selection(mesh, selection, edges, face_starts, corner_verts)


def delete_vertices(context, plans: list[VertexPlan]) -> BlenderEdit | None:
    """Delete the vertices marked in each plan (whole submeshes) with Blender's own edit-mode
    delete, keeping the user's selection on what stays. Called in Object Mode with every object
    of the session (an all-false mask deletes nothing there). Returns the edit still to run
    (Blender 4.2+), or None when the deletion is done (older versions, through Object Mode)."""
    objects = [plan.ob for plan in plans]
    for plan in plans:
        edges, face_starts, _sizes, corner_verts = mesh_io.read_topology(plan.ob.data)
        mesh_io.write_selection(plan.ob.data, plan.values, edges, face_starts, corner_verts)
        if SELECT_BY_ATTRIBUTE:
            mesh_io.write_point_flags(plan.ob.data, SAVED_SELECTION_ATTRIBUTE, plan.selection)
    if SELECT_BY_ATTRIBUTE:
        def action():
            bpy.ops.mesh.delete(type="VERT")
            _select_by_attribute(objects, SAVED_SELECTION_ATTRIBUTE)
            for ob in objects:
                mesh_io.remove_attributes(ob.data, [SAVED_SELECTION_ATTRIBUTE])
        return BlenderEdit(objects, action)
    in_edit_mode(context, objects, lambda: bpy.ops.mesh.delete(type="VERT"))
    for plan in plans:
        # Delete keeps the survivors in their order; submeshes go whole, so the survivors'
        # selection is the old one with rows removed.
        _reselect(plan.ob.data, plan.selection[~plan.values.astype(bool)])
    return None


def _pass_attribute(k):
    return f"{MERGE_PASS_ATTRIBUTE}_{k}"


def merge_by_distance(context, plans: list[VertexPlan], distance, progress=None) -> BlenderEdit | None:
    """Merge by distance inside submeshes with Blender's own Merge by Distance, pass by pass as
    core.merge_passes planned (each plan's values: the pass per vertex). Called in Object Mode
    with every object of the session. Returns the edit still to run (Blender 4.2+), or None when
    the merge is done (older versions, one round trip through Object Mode per pass).
    ``progress(k, passes)`` is called after each pass."""
    objects = [plan.ob for plan in plans]
    passes = max(int(plan.values.max()) + 1 for plan in plans)
    merge = lambda: bpy.ops.mesh.remove_doubles(threshold=distance, use_unselected=False)
    if SELECT_BY_ATTRIBUTE:
        names = [_pass_attribute(k) for k in range(passes)] + [SAVED_SELECTION_ATTRIBUTE]
        for plan in plans:
            for k in range(passes):
                mesh_io.write_point_flags(plan.ob.data, _pass_attribute(k), plan.values == k)
            mesh_io.write_point_flags(plan.ob.data, SAVED_SELECTION_ATTRIBUTE, plan.selection)

        def action():
            for k in range(passes):
                _select_by_attribute(objects, _pass_attribute(k))
                merge()
                if progress:
                    progress(k + 1, passes)
            _select_by_attribute(objects, SAVED_SELECTION_ATTRIBUTE)
            for ob in objects:
                mesh_io.remove_attributes(ob.data, names)
        return BlenderEdit(objects, action)

    # Blender < 4.2: the pass and the selection ride along in attributes (a merged vertex keeps
    # its target's values, and every vertex of a cluster has the same pass).
    for plan in plans:
        mesh = plan.ob.data
        mesh.attributes.new(MERGE_PASS_ATTRIBUTE, "INT", "POINT").data.foreach_set("value", plan.values)
        mesh_io.write_point_flags(mesh, SAVED_SELECTION_ATTRIBUTE, plan.selection)
    try:
        for k in range(passes):
            for ob in objects:
                _reselect(ob.data, mesh_io.read_point_values(ob.data, MERGE_PASS_ATTRIBUTE, np.int32) == k)
            in_edit_mode(context, objects, merge)
            if progress:
                progress(k + 1, passes)
    finally:
        for ob in objects:
            selection = mesh_io.read_point_values(ob.data, SAVED_SELECTION_ATTRIBUTE, bool)
            mesh_io.remove_attributes(ob.data, [MERGE_PASS_ATTRIBUTE, SAVED_SELECTION_ATTRIBUTE])
            _reselect(ob.data, selection)
    return None


def vertex_total(objects) -> int:
    """Vertices of these meshes now, in Edit Mode (the edit mesh) or Object Mode."""
    import bmesh

    return sum(len(bmesh.from_edit_mesh(ob.data).verts) if ob.mode == "EDIT" else len(ob.data.vertices)
               for ob in objects)

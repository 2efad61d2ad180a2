"""Blender mesh reads and writes of the submesh tools (select, dedup, merge, pack UVs).

A sibling of ``mesh_io``: every transfer goes through ``foreach_get``/``foreach_set`` on NumPy
buffers; nothing loops over vertices, edges or faces in Python. Geometry is removed by Blender's
own edit-mode operators (``mesh.delete``, ``mesh.remove_doubles``) on a selection computed in
the core, so every attribute, UV map, vertex group and material follows as Blender moves it.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import bpy
import numpy as np

from . import core, mesh_io

MERGE_PASS_ATTRIBUTE = "boxmarch_merge_pass"
SAVED_SELECTION_ATTRIBUTE = "boxmarch_saved_selection"


class ToolInputError(ValueError):
    """A mesh the tool cannot work on; the message says why. Nothing was changed."""


@dataclass
class MeshArrays:
    positions: np.ndarray
    edges: np.ndarray
    face_starts: np.ndarray
    face_sizes: np.ndarray
    corner_verts: np.ndarray
    submesh_of_vertex: np.ndarray
    submesh_count: int

    @property
    def topology(self):
        return self.positions, self.edges, self.face_starts, self.face_sizes, self.corner_verts


def tool_objects(context):
    """Mesh objects the tools work on, one per mesh datablock: those in Edit Mode, or the
    selected ones in Object Mode."""
    if context.mode == "EDIT_MESH":
        objects = context.objects_in_mode_unique_data
    else:
        objects = context.selected_objects
    unique = {}
    for ob in objects:
        if ob.type == "MESH" and ob.data.name_full not in unique:
            unique[ob.data.name_full] = ob
    return list(unique.values())


@contextmanager
def object_mode(context):
    """Leave Edit Mode (Blender writes the edit mesh back) for the body, return afterwards."""
    edit = context.mode == "EDIT_MESH"
    if edit:
        bpy.ops.object.mode_set(mode="OBJECT")
    try:
        yield edit
    finally:
        if edit:
            bpy.ops.object.mode_set(mode="EDIT")


def read_mesh(mesh, need_faces=False) -> MeshArrays:
    """The mesh's arrays and submeshes. Raises ToolInputError (naming the mesh) when the mesh is
    linked, empty, without faces (if ``need_faces``) or holds NaN/infinite coordinates."""
    if mesh.library is not None:
        raise ToolInputError(f"mesh '{mesh.name}' is linked from a library and cannot be changed")
    if len(mesh.vertices) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' is empty")
    if need_faces and len(mesh.polygons) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' has no faces")
    positions = mesh_io.read_positions(mesh)
    topology = mesh_io.read_topology(mesh)
    try:
        core.validate_mesh(positions, *topology)
    except ValueError as error:
        raise ToolInputError(f"mesh '{mesh.name}': {error}") from None
    ids, count = core.find_submeshes(positions, *topology)
    return MeshArrays(positions, *topology, ids, count)


def _flags(mesh, attribute, collection, domain_size, prop="select") -> np.ndarray:
    """A boolean flag per element: Blender 4+ keeps it in an internal attribute (absent when no
    element has it), 3.x in the elements themselves."""
    values = np.zeros(domain_size, bool)
    attr = mesh.attributes.get(attribute)
    if attr is not None:
        attr.data.foreach_get("value", values)
    elif bpy.app.version < (4, 0, 0):
        collection.foreach_get(prop, values)
    return values


def read_vertex_selection(mesh) -> np.ndarray:
    return mesh_io.read_vertex_selection(mesh).astype(bool)


def read_face_selection(mesh) -> np.ndarray:
    return _flags(mesh, ".select_poly", mesh.polygons, len(mesh.polygons))


def hidden_vertices(mesh) -> np.ndarray:
    return _flags(mesh, ".hide_vert", mesh.vertices, len(mesh.vertices), "hide")


def _write_flags(mesh, attribute, domain, collection, values):
    if bpy.app.version >= (4, 0, 0):
        attr = mesh.attributes.get(attribute)
        if attr is not None and (attr.data_type != "BOOLEAN" or attr.domain != domain):
            # Seen in 5.0.1: update(calc_edges=True) on a mesh built from arrays can leave an
            # INT32_2D '.select_edge'; RNA access to edge selection then crashes. Replace it.
            mesh.attributes.remove(attr)
            attr = None
        if attr is None:
            attr = mesh.attributes.new(attribute, "BOOLEAN", domain)
        attr.data.foreach_set("value", values)
    else:
        collection.foreach_set("select", values)


def write_selection(mesh, arrays: MeshArrays, vertex_selected) -> None:
    """Select exactly these vertices, the edges between two of them and the faces whose corners
    all are, as Blender's vertex selection mode would flush them."""
    vertex_selected = np.asarray(vertex_selected, bool)
    edge_selected = vertex_selected[arrays.edges[:, 0]] & vertex_selected[arrays.edges[:, 1]]
    if len(arrays.face_starts):
        face_selected = np.logical_and.reduceat(vertex_selected[arrays.corner_verts], arrays.face_starts)
    else:
        face_selected = np.zeros(0, bool)
    _write_flags(mesh, ".select_vert", "POINT", mesh.vertices, vertex_selected)
    _write_flags(mesh, ".select_edge", "EDGE", mesh.edges, edge_selected)
    _write_flags(mesh, ".select_poly", "FACE", mesh.polygons, face_selected)
    mesh.update()


def delete_submeshes(context, plans) -> None:
    """Delete whole submeshes with Blender's own edit-mode delete, keeping the user's selection
    on what stays. ``plans``: (object, arrays, delete mask per vertex, selection per vertex).
    Expects Object Mode with the objects selected; returns in Object Mode."""
    for ob, arrays, delete, _selection in plans:
        write_selection(ob.data, arrays, delete)
    _in_edit_mode(context, [ob for ob, *_ in plans], lambda: bpy.ops.mesh.delete(type="VERT"))
    for ob, _arrays, delete, selection in plans:
        # Delete keeps the survivors in their order; submeshes go whole, so the survivors'
        # topology is the old one with rows removed.
        write_selection(ob.data, read_mesh(ob.data), selection[~delete])


def _in_edit_mode(context, objects, action):
    """Run ``action`` (an edit-mode operator call) with exactly ``objects`` in Edit Mode."""
    view_layer = context.view_layer
    previous_active = view_layer.objects.active
    previous_selected = [ob for ob in context.selected_objects]
    for ob in previous_selected:
        ob.select_set(False)
    for ob in objects:
        ob.select_set(True)
    view_layer.objects.active = objects[0]
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        action()
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
        for ob in objects:
            ob.select_set(False)
        for ob in previous_selected:
            ob.select_set(True)
        view_layer.objects.active = previous_active


def merge_by_distance(context, plans, distance, progress=None) -> int:
    """Merge by distance inside submeshes with Blender's own Merge by Distance, pass by pass as
    core.merge_passes planned. ``plans``: (object, arrays, pass per vertex, selection per
    vertex). Expects and returns Object Mode. Returns the number of vertices removed."""
    before = sum(len(ob.data.vertices) for ob, *_ in plans)
    passes = max(int(passes.max()) + 1 for _ob, _arrays, passes, _sel in plans)
    for ob, _arrays, pass_of_vertex, selection in plans:
        mesh = ob.data
        # Kept in attributes: Blender carries them through the merges (a merged vertex keeps
        # its target's values, and every vertex of a cluster has the same pass).
        mesh.attributes.new(MERGE_PASS_ATTRIBUTE, "INT", "POINT").data.foreach_set("value", pass_of_vertex)
        mesh.attributes.new(SAVED_SELECTION_ATTRIBUTE, "BOOLEAN", "POINT").data.foreach_set("value", selection)
    try:
        for k in range(passes):
            for ob, *_ in plans:
                mesh = ob.data
                pass_of_vertex = np.empty(len(mesh.vertices), np.int32)
                mesh.attributes[MERGE_PASS_ATTRIBUTE].data.foreach_get("value", pass_of_vertex)
                write_selection(mesh, read_mesh(mesh), pass_of_vertex == k)
            _in_edit_mode(context, [ob for ob, *_ in plans],
                          lambda: bpy.ops.mesh.remove_doubles(threshold=distance, use_unselected=False))
            if progress:
                progress(k + 1)
    finally:
        for ob, *_ in plans:
            mesh = ob.data
            selection = np.empty(len(mesh.vertices), bool)
            mesh.attributes[SAVED_SELECTION_ATTRIBUTE].data.foreach_get("value", selection)
            for name in (MERGE_PASS_ATTRIBUTE, SAVED_SELECTION_ATTRIBUTE):
                mesh.attributes.remove(mesh.attributes[name])
            write_selection(mesh, read_mesh(mesh), selection)
    return before - sum(len(ob.data.vertices) for ob, *_ in plans)


def uv_map_name(mesh, requested: str) -> str:
    """The UV map to pack: ``requested`` by name, or the active one when empty."""
    if len(mesh.uv_layers) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' has no UV map")
    if not requested:
        return mesh.uv_layers.active.name if mesh.uv_layers.active else mesh.uv_layers[0].name
    if requested not in mesh.uv_layers:
        raise ToolInputError(f"mesh '{mesh.name}' has no UV map named '{requested}'")
    return requested


def read_uv(mesh, name) -> np.ndarray:
    return mesh_io._read_uv(mesh, name, len(mesh.loops))


def write_uv(mesh, name, values) -> None:
    mesh_io._write_uv(mesh, name, np.ascontiguousarray(values, np.float32))
    mesh.update()


def world_heights(ob, positions) -> np.ndarray:
    """World Z of every vertex (float32), from the object's world matrix."""
    row = np.array(ob.matrix_world, np.float64)[2]
    return (positions.astype(np.float64) @ row[:3] + row[3]).astype(np.float32)

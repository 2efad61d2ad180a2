"""Blender mesh reads and writes of the submesh tools (select, dedup, merge, pack UVs).

A sibling of ``mesh_io``: every transfer goes through ``foreach_get``/``foreach_set`` on NumPy
buffers; nothing loops over vertices, edges or faces in Python. Geometry changes are either a
rebuild from arrays the core computed (every generic attribute carried from the old element each
new one comes from), or, where a rebuild could lose data (vertex groups, shape keys, Blender
before 4.1), Blender's own edit-mode operators (``mesh.delete``, ``mesh.remove_doubles``) on a
selection the core planned.
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


# Blender 4.2+ selects by a boolean attribute inside Edit Mode: the tools then change geometry and
# restore the selection in one Edit Mode session (leaving and re-entering Edit Mode on a million
# vertices costs most of a second). Older versions take a round trip through Object Mode.
SELECT_BY_ATTRIBUTE = bpy.app.version >= (4, 2, 0)


def _edit_session(context, objects, edit, action):
    """Run ``action`` in Edit Mode: right away when the operator runs in Edit Mode (already
    re-entered), else with exactly ``objects`` in Edit Mode and back to Object Mode after."""
    if edit:
        action()
    else:
        _in_edit_mode(context, objects, action)


def _in_edit_mode(context, objects, action):
    """Run ``action`` with exactly ``objects`` in Edit Mode, from and back to Object Mode."""
    view_layer = context.view_layer
    previous_active = view_layer.objects.active
    previous_selected = list(context.selected_objects)
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


def _select_by_attributes(objects, name):
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


def _remove_attributes(objects, names):
    for ob in objects:
        for name in names:
            if name in ob.data.attributes:
                ob.data.attributes.remove(ob.data.attributes[name])


def _store_flags(mesh, name, values):
    if name in mesh.attributes:
        mesh.attributes.remove(mesh.attributes[name])
    mesh.attributes.new(name, "BOOLEAN", "POINT").data.foreach_set("value", np.asarray(values, bool))


def delete_vertices(context, plans, edit) -> None:
    """Delete vertices (whole submeshes) with Blender's own edit-mode delete, keeping the user's
    selection on what stays. ``plans``: (object, arrays, delete mask, saved selection) for every
    object in the session (an all-false mask deletes nothing there). Called in Object Mode; the
    deletion itself runs after the operator is back in Edit Mode when ``edit``."""
    objects = [ob for ob, *_ in plans]
    for ob, arrays, delete, selection in plans:
        write_selection(ob.data, arrays, delete)
        if SELECT_BY_ATTRIBUTE:
            _store_flags(ob.data, SAVED_SELECTION_ATTRIBUTE, selection)
    if SELECT_BY_ATTRIBUTE:
        def action():
            bpy.ops.mesh.delete(type="VERT")
            _select_by_attributes(objects, SAVED_SELECTION_ATTRIBUTE)
            _remove_attributes(objects, [SAVED_SELECTION_ATTRIBUTE])
        return lambda: _edit_session(context, objects, edit, action)
    _in_edit_mode(context, objects, lambda: bpy.ops.mesh.delete(type="VERT"))
    for ob, _arrays, delete, selection in plans:
        # Delete keeps the survivors in their order; submeshes go whole, so the survivors'
        # topology is the old one with rows removed.
        write_selection(ob.data, read_mesh(ob.data), selection[~delete])
    return None


def _pass_attribute(k):
    return f"{MERGE_PASS_ATTRIBUTE}_{k}"


def merge_by_distance(context, plans, distance, edit, progress=None):
    """Merge by distance inside submeshes with Blender's own Merge by Distance, pass by pass as
    core.merge_passes planned. ``plans``: (object, arrays, pass per vertex, saved selection)
    for every object in the session (pass -1 everywhere: nothing merges there). Called in
    Object Mode. Returns (action, vertex counter): the action runs the merge (when ``edit``, once
    the operator is back in Edit Mode), the counter tells the vertex total afterwards."""
    objects = [ob for ob, *_ in plans]
    passes = max(int(p.max()) + 1 for _ob, _arrays, p, _sel in plans)
    merge = lambda: bpy.ops.mesh.remove_doubles(threshold=distance, use_unselected=False)
    if SELECT_BY_ATTRIBUTE:
        names = [_pass_attribute(k) for k in range(passes)] + [SAVED_SELECTION_ATTRIBUTE]
        for ob, arrays, pass_of_vertex, selection in plans:
            for k in range(passes):
                _store_flags(ob.data, _pass_attribute(k), pass_of_vertex == k)
            _store_flags(ob.data, SAVED_SELECTION_ATTRIBUTE, selection)

        def action():
            for k in range(passes):
                _select_by_attributes(objects, _pass_attribute(k))
                merge()
                if progress:
                    progress(k + 1, passes)
            _select_by_attributes(objects, SAVED_SELECTION_ATTRIBUTE)
            _remove_attributes(objects, names)
        return lambda: _edit_session(context, objects, edit, action)

    # Blender < 4.2: one round trip through Object Mode per pass. The pass and the selection
    # ride along in attributes (a merged vertex keeps its target's values, and every vertex of
    # a cluster has the same pass).
    for ob, _arrays, pass_of_vertex, selection in plans:
        mesh = ob.data
        mesh.attributes.new(MERGE_PASS_ATTRIBUTE, "INT", "POINT").data.foreach_set("value", pass_of_vertex)
        _store_flags(mesh, SAVED_SELECTION_ATTRIBUTE, selection)
    try:
        for k in range(passes):
            for ob in objects:
                mesh = ob.data
                pass_of_vertex = np.empty(len(mesh.vertices), np.int32)
                mesh.attributes[MERGE_PASS_ATTRIBUTE].data.foreach_get("value", pass_of_vertex)
                write_selection(mesh, read_mesh(mesh), pass_of_vertex == k)
            _in_edit_mode(context, objects, merge)
            if progress:
                progress(k + 1, passes)
    finally:
        for ob in objects:
            mesh = ob.data
            selection = np.empty(len(mesh.vertices), bool)
            mesh.attributes[SAVED_SELECTION_ATTRIBUTE].data.foreach_get("value", selection)
            _remove_attributes([ob], [MERGE_PASS_ATTRIBUTE, SAVED_SELECTION_ATTRIBUTE])
            write_selection(mesh, read_mesh(mesh), selection)
    return None


def vertex_total(objects) -> int:
    """Vertices of these meshes now, in Edit Mode (the edit mesh) or Object Mode."""
    import bmesh

    return sum(len(bmesh.from_edit_mesh(ob.data).verts) if ob.mode == "EDIT" else len(ob.data.vertices)
               for ob in objects)


# Attribute types the rebuild carries, with the bulk property and components per element.
_ATTRIBUTE_LAYOUT = {
    "FLOAT": ("value", 1, np.float32), "INT": ("value", 1, np.int32), "BOOLEAN": ("value", 1, bool),
    "INT8": ("value", 1, np.int32), "FLOAT_VECTOR": ("vector", 3, np.float32),
    "FLOAT2": ("vector", 2, np.float32), "FLOAT_COLOR": ("color", 4, np.float32),
    "BYTE_COLOR": ("color_srgb", 4, np.float32), "INT32_2D": ("value", 2, np.int32),
    "INT16_2D": ("value", 2, np.int32), "QUATERNION": ("value", 4, np.float32),
    "FLOAT4X4": ("value", 16, np.float32),
}
_TOPOLOGY_ATTRIBUTES = {"position", ".edge_verts", ".corner_vert", ".corner_edge"}


def can_rebuild(mesh) -> bool:
    """True when rebuilding the mesh from arrays keeps everything it holds: Blender 4.1+ (all
    data in generic attributes), no shape keys, no object using it with vertex groups, and only
    attribute types the rebuild knows."""
    if bpy.app.version < (4, 1, 0) or mesh.shape_keys is not None:
        return False
    if any(ob.data == mesh and len(ob.vertex_groups) for ob in bpy.data.objects):
        return False
    return all(a.data_type in _ATTRIBUTE_LAYOUT for a in mesh.attributes if a.name not in _TOPOLOGY_ATTRIBUTES)


def _set_topology(mesh, attribute, prop, collection, rna_prop, values):
    attr = mesh.attributes.get(attribute)
    values = np.ascontiguousarray(values).reshape(-1)
    if attr is not None:
        attr.data.foreach_set(prop, values)
    else:
        collection.foreach_set(rna_prop, values)


def read_corner_edges(mesh) -> np.ndarray:
    """Each corner's edge (to the next corner of its face), int32."""
    values = np.empty(len(mesh.loops), np.int32)
    attr = mesh.attributes.get(".corner_edge")
    if attr is not None:
        attr.data.foreach_get("value", values)
    else:
        mesh.loops.foreach_get("edge_index", values)
    return values


def rebuild_welded(mesh, merged_positions, weld) -> None:
    """Replace the mesh's geometry by the welded topology (core.weld), carrying every attribute
    over from the old element each new one comes from. Object Mode; expects can_rebuild."""
    captured = []
    for attr in mesh.attributes:
        if attr.name in _TOPOLOGY_ATTRIBUTES:
            continue
        prop, components, dtype = _ATTRIBUTE_LAYOUT[attr.data_type]
        values = np.empty(len(attr.data) * components, dtype)
        attr.data.foreach_get(prop, values)
        captured.append((attr.name, attr.data_type, attr.domain, values.reshape(len(attr.data), components)))
    active_uv = mesh.uv_layers.active.name if mesh.uv_layers.active else None
    render_uv = next((uv.name for uv in mesh.uv_layers if uv.active_render), None)
    colors = mesh.color_attributes
    active_color, default_color = colors.active_color_name, colors.default_color_name

    mesh.clear_geometry()
    # Topology through its internal attributes where they exist (contiguous, much faster than
    # the per-element RNA of vertices, edges and loops).
    mesh.vertices.add(len(weld["vertex_source"]))
    _set_topology(mesh, "position", "vector", mesh.vertices, "co", merged_positions[weld["vertex_source"]])
    mesh.edges.add(len(weld["edge_source"]))
    _set_topology(mesh, ".edge_verts", "value", mesh.edges, "vertices", weld["edges"])
    mesh.loops.add(len(weld["corner_source"]))
    _set_topology(mesh, ".corner_vert", "value", mesh.loops, "vertex_index", weld["corner_verts"])
    _set_topology(mesh, ".corner_edge", "value", mesh.loops, "edge_index", weld["corner_edges"])
    mesh.polygons.add(len(weld["face_source"]))
    mesh.polygons.foreach_set("loop_start", np.ascontiguousarray(weld["face_starts"]))
    # Adding elements may create flags the mesh did not have (new faces come selected): drop them.
    captured_names = {name for name, *_ in captured}
    for name in [a.name for a in mesh.attributes if a.name not in _TOPOLOGY_ATTRIBUTES and a.name not in captured_names]:
        mesh.attributes.remove(mesh.attributes[name])
    source = {"POINT": weld["vertex_source"], "EDGE": weld["edge_source"], "FACE": weld["face_source"],
              "CORNER": weld["corner_source"]}
    for name, data_type, domain, values in captured:
        attr = mesh.attributes.get(name)
        if attr is None or attr.data_type != data_type or attr.domain != domain:
            if attr is not None:
                mesh.attributes.remove(attr)
            attr = mesh.attributes.new(name, data_type, domain)
        prop = _ATTRIBUTE_LAYOUT[data_type][0]
        attr.data.foreach_set(prop, np.ascontiguousarray(values[source[domain]]).reshape(-1))
    if active_uv and active_uv in mesh.uv_layers:
        mesh.uv_layers.active = mesh.uv_layers[active_uv]
    if render_uv and render_uv in mesh.uv_layers:
        mesh.uv_layers[render_uv].active_render = True
    if active_color:
        colors.active_color_name = active_color
    if default_color:
        colors.default_color_name = default_color
    mesh.update()


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

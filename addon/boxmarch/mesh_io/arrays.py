"""Geometry, selection and UV maps of a Blender mesh as NumPy arrays, and meshes made from arrays."""
from __future__ import annotations

import bpy
import numpy as np

from .. import core


def one_object_per_mesh(objects) -> list:
    """The mesh objects among ``objects``, one per mesh datablock (the first that uses it): the
    jobs change mesh data, and a mesh shared by linked duplicates must be changed once."""
    unique = {}
    for ob in objects:
        if ob.type == "MESH" and ob.data.name_full not in unique:
            unique[ob.data.name_full] = ob
    return list(unique.values())


def new_mesh(name, positions, face_starts, face_sizes, corner_verts, edges=None):
    """A new mesh datablock holding these faces, plus ``edges`` (E, 2) when given (loose edges
    need them); Blender derives the faces' edges (and each corner's edge), as in any mesh made in
    the editor."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.asarray(positions, np.float32).reshape(-1))
    if edges is not None and len(edges):
        mesh.edges.add(len(edges))
        mesh.edges.foreach_set("vertices", np.asarray(edges, np.int32).reshape(-1))
    mesh.loops.add(len(corner_verts))
    mesh.loops.foreach_set("vertex_index", np.asarray(corner_verts, np.int32))
    mesh.polygons.add(len(face_starts))
    mesh.polygons.foreach_set("loop_start", np.asarray(face_starts, np.int32))
    if bpy.app.version < (4, 0, 0):  # 4.0 derives sizes from the starts
        mesh.polygons.foreach_set("loop_total", np.asarray(face_sizes, np.int32))
    mesh.update(calc_edges=True)
    # The edges Blender derives get a '.select_edge' that is wrong for a mesh with nothing selected:
    # 4.2 selects every new edge; 5.0.1 leaves an INT32_2D copy of the edge layout, and RNA access
    # to edge selection then crashes. Selection layers are optional: absent means none selected.
    select_edge = mesh.attributes.get(".select_edge")
    if select_edge is not None:
        mesh.attributes.remove(select_edge)
    return mesh


def _fast_attribute(mesh, name):
    """Blender 4+ keeps topology in internal attributes with contiguous storage (much faster to
    read than the per-element RNA of mesh.loops or mesh.edges); 3.x has none of them."""
    attr = mesh.attributes.get(name)
    return attr if attr is not None and name.startswith(".") else None


def _read_topology_ints(mesh, fast_name, collection, prop, width=1) -> np.ndarray:
    """int32 values of ``prop`` over ``collection`` (``width`` per element), from the internal
    attribute ``fast_name`` where this Blender has it."""
    values = np.empty(len(collection) * width, np.int32)
    attr = _fast_attribute(mesh, fast_name)
    if attr is not None:
        attr.data.foreach_get("value", values)
    else:
        collection.foreach_get(prop, values)
    return values


def read_positions(mesh) -> np.ndarray:
    """float32 (N, 3) object-space vertex positions."""
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    attr = mesh.attributes.get("position")
    if attr is not None and attr.data_type == "FLOAT_VECTOR" and bpy.app.version >= (4, 0, 0):
        attr.data.foreach_get("vector", positions)
    else:
        mesh.vertices.foreach_get("co", positions)
    return positions.reshape(-1, 3)


def read_topology(mesh):
    """(edges (E, 2), face_starts (F,), face_sizes (F,), corner_verts (C,)), all int32."""
    edges = _read_topology_ints(mesh, ".edge_verts", mesh.edges, "vertices", 2).reshape(-1, 2)
    corner_verts = _read_topology_ints(mesh, ".corner_vert", mesh.loops, "vertex_index")
    faces = None
    if _fast_attribute(mesh, ".corner_edge") is not None:
        faces = core.face_offsets_from_corner_edges(corner_verts, read_corner_edges(mesh), edges,
                                                    len(mesh.vertices), len(mesh.polygons), arrays_owned=True)
    if faces is None:
        face_starts = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_start", face_starts)
        face_sizes = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_total", face_sizes)
        faces = face_starts, face_sizes
    return edges, faces[0], faces[1], corner_verts


def read_triangles(mesh) -> np.ndarray:
    """int32 (T, 3) vertex indices of the mesh's triangulation (Blender's loop triangles)."""
    mesh.calc_loop_triangles()
    triangles = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    return triangles.reshape(-1, 3)


def read_corner_edges(mesh) -> np.ndarray:
    """Each corner's edge (to the next corner of its face), int32."""
    return _read_topology_ints(mesh, ".corner_edge", mesh.loops, "edge_index")


# ---------------------------------------------------------------------------------------------
# Selection and hiding (Object Mode data: leave Edit Mode first, edit_mode.object_mode)


def _flags(mesh, attribute, collection, domain_size, prop="select") -> np.ndarray:
    """A boolean flag per element: Blender 4+ keeps it in an internal attribute (absent when no
    element has it), 3.x in the elements themselves."""
    values = np.zeros(domain_size, bool)
    attr = _fast_attribute(mesh, attribute)
    if attr is not None:
        attr.data.foreach_get("value", values)
    elif bpy.app.version < (4, 0, 0):
        collection.foreach_get(prop, values)
    return values


def read_vertex_selection(mesh) -> np.ndarray:
    """bool per vertex, True where selected."""
    return _flags(mesh, ".select_vert", mesh.vertices, len(mesh.vertices))


def read_face_selection(mesh) -> np.ndarray:
    """bool per face, True where selected."""
    return _flags(mesh, ".select_poly", mesh.polygons, len(mesh.polygons))


def read_hidden_vertices(mesh) -> np.ndarray:
    """bool per vertex, True where hidden."""
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


def write_selection(mesh, vertex_selected, edges, face_starts, corner_verts) -> None:
    """Select exactly these vertices, the edges between two of them and the faces whose corners
    all are, as Blender's vertex selection mode would flush them (the topology is the mesh's,
    read_topology)."""
    vertex_selected = np.asarray(vertex_selected, bool)
    edge_selected = vertex_selected[edges[:, 0]] & vertex_selected[edges[:, 1]]
    if len(face_starts):
        face_selected = np.logical_and.reduceat(vertex_selected[corner_verts], face_starts)
    else:
        face_selected = np.zeros(0, bool)
    _write_flags(mesh, ".select_vert", "POINT", mesh.vertices, vertex_selected)
    _write_flags(mesh, ".select_edge", "EDGE", mesh.edges, edge_selected)
    _write_flags(mesh, ".select_poly", "FACE", mesh.polygons, face_selected)
    mesh.update()


def write_point_flags(mesh, name, values) -> None:
    """Store a boolean per vertex as the attribute ``name`` (replacing one of that name)."""
    if name in mesh.attributes:
        mesh.attributes.remove(mesh.attributes[name])
    mesh.attributes.new(name, "BOOLEAN", "POINT").data.foreach_set("value", np.asarray(values, bool))


def read_point_values(mesh, name, dtype) -> np.ndarray:
    """The per-vertex values of the attribute ``name`` (BOOLEAN as bool, INT as int32)."""
    values = np.empty(len(mesh.vertices), dtype)
    mesh.attributes[name].data.foreach_get("value", values)
    return values


def remove_attributes(mesh, names) -> None:
    for name in names:
        if name in mesh.attributes:
            mesh.attributes.remove(mesh.attributes[name])


# ---------------------------------------------------------------------------------------------
# UV maps


def _uv_buffer_accessor(uv_layer):
    """(collection, property) for bulk UV access: uv_layer.uv/'vector' from 3.5, data/'uv' before."""
    return (uv_layer.uv, "vector") if hasattr(uv_layer, "uv") else (uv_layer.data, "uv")


def read_uv(mesh, name) -> np.ndarray:
    """float32 (corners, 2) of the UV map ``name``."""
    buf = np.empty(len(mesh.loops) * 2, np.float32)
    collection, prop = _uv_buffer_accessor(mesh.uv_layers[name])
    collection.foreach_get(prop, buf)
    return buf.reshape(-1, 2)


def new_zero_uv(mesh, name) -> None:
    """A new UV map ``name`` holding (0, 0) at every corner. Where a mesh needs a first UV map only
    so the box channels that follow get their numbers, its values must not differ between the
    corners of one vertex: Blender's default fill (each face its own unit square) makes every
    exporter split a box's 8 vertices into 20."""
    mesh.uv_layers.new(name=name, do_init=False)
    write_uv(mesh, name, np.zeros((len(mesh.loops), 2), np.float32))


def one_normal_per_vertex(mesh) -> None:
    """Give every vertex of ``mesh`` one normal at all its corners: faces smooth, no sharp edges,
    custom normals back to the default. Exporters split a vertex wherever its corners' normals
    differ (a flat box: 24 vertices for 8); for a copy whose normals no decode reads."""
    mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), bool))
    sharp_edge = mesh.attributes.get("sharp_edge")  # 4.1+; before, sharp edges act only with auto smooth
    if sharp_edge is not None:
        mesh.attributes.remove(sharp_edge)
    if hasattr(mesh, "use_auto_smooth"):  # before 4.1: sharp edges and custom normals need it
        mesh.use_auto_smooth = False
    # 5.0 keeps custom normals in this attribute, and "free" ones differ between the corners of a
    # smooth fan; before 5.0 they are offsets per fan, so smooth faces without sharp edges merge them
    custom = mesh.attributes.get("custom_normal")
    if custom is not None:
        mesh.attributes.remove(custom)


def write_uv(mesh, name, values) -> None:
    """Store float32 (corners, 2) in the existing UV map ``name``."""
    values = np.ascontiguousarray(values, np.float32)
    # From 3.5 a UV map is a FLOAT2 attribute. Writing it through the attribute API un-shares the
    # array first; uv_layer.uv writes straight into an array a copied mesh (Shift+D) may share.
    attr = mesh.attributes.get(name)
    if attr is not None and attr.data_type == "FLOAT2":
        attr.data.foreach_set("vector", values.reshape(-1))
        return
    collection, prop = _uv_buffer_accessor(mesh.uv_layers[name])
    collection.foreach_set(prop, values.reshape(-1))

"""Rebuilding a mesh's geometry from arrays the core computed (core.weld, core.remove_vertices),
carrying every generic attribute over from the old element each new one comes from."""
from __future__ import annotations

import bpy
import numpy as np


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


def rebuild_blocker(mesh, welding: bool) -> str | None:
    """Why rebuilding the mesh from arrays would lose or change something it holds (then the tools
    run Blender's own delete or merge, which carry every layer), or None when the rebuild keeps
    everything. Blender before 4.1 keeps data outside generic attributes; so does any version
    for shape keys, vertex groups (deform weights), the Skin modifier's radii and a Multires
    modifier's displacements. Custom normals are stored relative to each vertex's corner fan,
    which a weld changes, and before 5.0 outside the attributes, as Freestyle marks were."""
    users = [ob for ob in bpy.data.objects if ob.data == mesh]
    if bpy.app.version < (4, 1, 0):
        return "Blender before 4.1"
    if mesh.shape_keys is not None:
        return "shape keys"
    if any(len(ob.vertex_groups) for ob in users):
        return "vertex groups"
    if len(mesh.skin_vertices):
        return "skin radii"
    if any(m.type == "MULTIRES" for ob in users for m in ob.modifiers):
        return "multires displacements"
    if mesh.has_custom_normals and (welding or "custom_normal" not in mesh.attributes):
        return "custom normals"
    if _freestyle_marks_outside_attributes(mesh):
        return "Freestyle marks"
    unknown = sorted({a.data_type for a in mesh.attributes
                      if a.name not in _TOPOLOGY_ATTRIBUTES and a.data_type not in _ATTRIBUTE_LAYOUT})
    return f"{', '.join(unknown)} attributes" if unknown else None


def _freestyle_marks_outside_attributes(mesh) -> bool:
    """True where the mesh has Freestyle edge or face marks in the layers Blender kept before 5.0
    (MeshEdge / MeshPolygon ``use_freestyle_mark``; 5.0 stores them as the generic attributes
    ``freestyle_edge`` / ``freestyle_face``, which the rebuild carries)."""
    for collection, rna in ((mesh.edges, bpy.types.MeshEdge), (mesh.polygons, bpy.types.MeshPolygon)):
        if "use_freestyle_mark" in rna.bl_rna.properties and len(collection):
            marks = np.zeros(len(collection), bool)
            collection.foreach_get("use_freestyle_mark", marks)
            if marks.any():
                return True
    return False


def _set_topology(mesh, attribute, prop, collection, rna_prop, values):
    attr = mesh.attributes.get(attribute)
    values = np.ascontiguousarray(values).reshape(-1)
    if attr is not None:
        attr.data.foreach_set(prop, values)
    else:
        collection.foreach_set(rna_prop, values)


def rebuild_welded(mesh, merged_positions, weld) -> None:
    """Replace the mesh's geometry by the welded topology (core.weld), carrying every attribute
    over from the old element each new one comes from. Object Mode; expects rebuild_blocker
    to be None."""
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

"""Rewriting a binary FBX file that Blender's exporter wrote: the one patch the skin-safe layouts
need in FBX. The exporter writes its own normals (the mesh's, deduplicated) and tangents
(MikkTSpace from each UV map); the NORMAL_FRAME layout needs the box frame there instead, as
exact numbers: each polygon corner's NORMAL (local z), TANGENT (local x) and binormal (local y).

Read and written with formats/fbx_container.py (the binary container, no Blender): every record
but the patched layer elements is written back with its values and type codes."""
from __future__ import annotations

import numpy as np

from . import fbx_container

# The frame vectors by layer element: (element, data, index or None).
_FRAME_LAYERS = {"NORMAL": (b"LayerElementNormal", b"Normals", b"NormalsIndex"),
                 "TANGENT": (b"LayerElementTangent", b"Tangents", None),
                 "BINORMAL": (b"LayerElementBinormal", b"Binormals", None)}


def replace_frame(path, frames_by_mesh: dict) -> None:
    """Write into the FBX file ``path``, for each Geometry named in ``frames_by_mesh`` (mesh name
    -> {"NORMAL", "TANGENT", "BINORMAL": float64 (polygon corners, 3)} in the file's axes, in
    Blender's corner order, which the file's PolygonVertexIndex keeps), those vectors as the
    geometry's normals (ByPolygonVertex, one per corner) and as every tangent and binormal layer.
    Raises ValueError, and leaves the file as it was, when the file is no binary FBX 7.x that
    formats/fbx_container.py reads, or a named geometry, its normal or tangent layers or their
    records are missing."""
    document = fbx_container.read(path)
    objects = next((node for node in document.nodes if node.name == b"Objects"), None)
    by_name = {}
    for geometry in (objects.children if objects else ()):
        if geometry.name == b"Geometry" and len(geometry.props) > 1:
            by_name[_geometry_name(geometry)] = geometry
    missing = set(frames_by_mesh) - set(by_name)
    if missing:
        raise ValueError(f"the FBX exporter wrote no geometry named {sorted(missing)}")
    for name, frames in frames_by_mesh.items():
        geometry = by_name[name]
        polygon_vertices = _record(geometry, b"PolygonVertexIndex", name)
        if polygon_vertices.types != b"i":
            raise ValueError(f"geometry '{name}': PolygonVertexIndex holds no int32 array")
        corners = len(polygon_vertices.props[0])
        for channel, (element, data_name, index_name) in _FRAME_LAYERS.items():
            layers = [layer for layer in geometry.children if layer.name == element]
            if not layers:
                raise ValueError(f"geometry '{name}' has no {element.decode()} (tangents need triangles and quads)")
            vectors = np.asarray(frames[channel], np.float64).reshape(-1, 3)
            if len(vectors) != corners:
                raise ValueError(f"geometry '{name}': {len(vectors)} {channel} vectors for {corners} corners")
            for layer in layers:
                _set(_record(layer, b"MappingInformationType", name), b"S", b"ByPolygonVertex")
                _set(_record(layer, data_name, name), b"d", vectors.reshape(-1))
                # an index (IndexToDirect normals) and per-vector weights, where the exporter
                # wrote them, stay one per vector
                index = layer.child(index_name) if index_name else None
                if index is not None:
                    _set(index, b"i", np.arange(corners, dtype=np.int32))
                weights = layer.child(data_name + b"W")
                if weights is not None:
                    _set(weights, b"d", np.ones(corners))
    fbx_container.write(path, document)  # nothing is written unless every geometry checked out


def _geometry_name(geometry) -> str:
    """The mesh name of a Geometry record: its second property, a string "NAME\\x00\\x01Geometry"."""
    if geometry.types[1:2] != b"S" or not isinstance(geometry.props[1], bytes):
        raise ValueError(f"a Geometry record's name is a '{geometry.types[1:2].decode(errors='replace')}' "
                         f"property, not a string")
    try:
        return geometry.props[1].split(b"\x00\x01")[0].decode()
    except UnicodeDecodeError:
        raise ValueError(f"a Geometry record's name {geometry.props[1][:40]!r} is not UTF-8 text") from None


def _record(parent, name, mesh):
    record = parent.child(name)
    if record is None:
        raise ValueError(f"geometry '{mesh}': {parent.name.decode()} has no {name.decode()}")
    return record


def _set(record, kind, value):
    record.props, record.types = [value], kind

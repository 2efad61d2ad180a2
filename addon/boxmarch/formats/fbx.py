"""Rewriting a binary FBX file that Blender's exporter wrote: the one patch the skin-safe layouts
need in FBX. The exporter writes its own normals (the mesh's, deduplicated) and tangents
(MikkTSpace from each UV map); the NORMAL_FRAME layout needs the box frame there instead, as
exact numbers: each polygon corner's NORMAL (local z), TANGENT (local x) and binormal (local y).

Read and written with the FBX add-on's own container code (io_scene_fbx.parse_fbx and
encode_bin, bundled with Blender); nothing else in the file changes."""
from __future__ import annotations

import numpy as np
from io_scene_fbx import data_types, encode_bin, parse_fbx

# Property type code -> FBXElem method writing it (Blender 3.4's FBX add-on has no CHAR type).
_ADDERS = {getattr(data_types, kind): "add_" + method for kind, method in (
    ("BOOL", "bool"), ("CHAR", "char"), ("INT8", "int8"), ("INT16", "int16"), ("INT32", "int32"), ("INT64", "int64"),
    ("FLOAT32", "float32"), ("FLOAT64", "float64"), ("BYTES", "bytes"), ("STRING", "string"),
    ("INT32_ARRAY", "int32_array"), ("INT64_ARRAY", "int64_array"), ("FLOAT32_ARRAY", "float32_array"),
    ("FLOAT64_ARRAY", "float64_array"), ("BOOL_ARRAY", "bool_array"), ("BYTE_ARRAY", "byte_array"))
    if hasattr(data_types, kind) and hasattr(encode_bin.FBXElem, "add_" + method)}
_ARRAYS = {getattr(data_types, kind) for kind in ("INT32_ARRAY", "INT64_ARRAY", "FLOAT32_ARRAY", "FLOAT64_ARRAY",
                                                 "BOOL_ARRAY", "BYTE_ARRAY") if hasattr(data_types, kind)}
# The frame vectors by layer element: (element, data, index or None).
_FRAME_LAYERS = {"NORMAL": (b"LayerElementNormal", b"Normals", b"NormalsIndex"),
                 "TANGENT": (b"LayerElementTangent", b"Tangents", None),
                 "BINORMAL": (b"LayerElementBinormal", b"Binormals", None)}


def _writable(parsed, replace=None):
    """encode_bin.FBXElem of a parsed element; ``replace(elem)`` may return new props (values,
    type codes) for an element."""
    out = encode_bin.FBXElem(parsed.id)
    props = replace(parsed) if replace else None
    values, kinds = props if props is not None else (parsed.props, parsed.props_type)
    for value, kind in zip(values, kinds):
        if kind in _ARRAYS:
            value = np.ascontiguousarray(value)
        getattr(out, _ADDERS[kind])(value)
    out.elems = [_writable(child, replace) for child in parsed.elems]
    return out


def _child(elem, name):
    return next((c for c in elem.elems if c.id == name), None)


def replace_frame(path, frames_by_mesh: dict) -> None:
    """Write into the FBX file ``path``, for each Geometry named in ``frames_by_mesh`` (mesh name
    -> {"NORMAL", "TANGENT", "BINORMAL": float64 (polygon corners, 3)} in the file's axes, in
    Blender's corner order, which the file's PolygonVertexIndex keeps), those vectors as the
    geometry's normals (ByPolygonVertex, one per corner) and as every tangent and binormal layer.
    Raises ValueError when a named geometry, or its normal or tangent layers, is missing."""
    root, version = parse_fbx.parse(path)
    objects = _child(root, b"Objects")
    by_name = {}
    for geometry in (objects.elems if objects else ()):
        if geometry.id == b"Geometry" and len(geometry.props) > 1:
            by_name[geometry.props[1].split(b"\x00\x01")[0].decode()] = geometry
    missing = set(frames_by_mesh) - set(by_name)
    if missing:
        raise ValueError(f"the FBX exporter wrote no geometry named {sorted(missing)}")
    patches = {}
    for name, frames in frames_by_mesh.items():
        geometry = by_name[name]
        corners = len(_child(geometry, b"PolygonVertexIndex").props[0])
        for channel, (element, data_name, index_name) in _FRAME_LAYERS.items():
            layers = [layer for layer in geometry.elems if layer.id == element]
            if not layers:
                raise ValueError(f"geometry '{name}' has no {element.decode()} (tangents need triangles and quads)")
            vectors = np.asarray(frames[channel], np.float64).reshape(-1, 3)
            if len(vectors) != corners:
                raise ValueError(f"geometry '{name}': {len(vectors)} {channel} vectors for {corners} corners")
            for layer in layers:
                patches[id(_child(layer, b"MappingInformationType"))] = ([b"ByPolygonVertex"], [data_types.STRING])
                patches[id(_child(layer, data_name))] = ([vectors.reshape(-1)], [data_types.FLOAT64_ARRAY])
                if index_name is not None:
                    patches[id(_child(layer, index_name))] = ([np.arange(corners, dtype=np.int32)],
                                                             [data_types.INT32_ARRAY])
                # per-vector weights, where the exporter wrote them, stay one per vector
                weights = _child(layer, data_name + b"W")
                if weights is not None:
                    patches[id(weights)] = ([np.ones(corners)], [data_types.FLOAT64_ARRAY])
    encode_bin.write(path, _writable(root, lambda elem: patches.get(id(elem))), version)

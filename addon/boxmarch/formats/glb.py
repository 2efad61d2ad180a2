"""Reading and rewriting glTF binary (.glb) files: the container, accessors, and the one patch
the glTF presets need (the layout's channels as float32 accessors). Blender-free.

Blender's exporter cannot write what the layouts need: it writes colours as normalised unsigned
shorts clipped to [0, 1] (4.x, 5.0; 3.4 writes floats but attaches CORNER-domain colours to the
wrong vertices), flips every UV map's v, and writes its own normals and tangents. So the presets
export each vertex's *index* as the colour (exact in two 16-bit channels), and this module
replaces it with the layout's channels (float COLOR_0, NORMAL, TANGENT, TEXCOORD_1..n) looked up
by index: the file holds exactly the float32 numbers of the layout, with no flip to undo.
"""
from __future__ import annotations

import json
import struct

import numpy as np

from . import files

GLB_MAGIC, CHUNK_JSON, CHUNK_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
COMPONENT_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
                    5125: np.uint32, 5126: np.float32}
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
FLOAT, ARRAY_BUFFER = 5126, 34962
INDEX_COLOUR_SCALE = 65535.0
GLTF_ATTRIBUTES = {"COLOR": "COLOR_0", "NORMAL": "NORMAL", "TANGENT": "TANGENT"}


def read(path):
    """(gltf dict, bin bytes) of a .glb file; ValueError if it is not one."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 20 or struct.unpack_from("<I", data, 0)[0] != GLB_MAGIC:
        raise ValueError(f"{path} is not a glTF binary file")
    gltf, binary, offset = None, b"", 12
    while offset + 8 <= len(data):
        length, kind = struct.unpack_from("<II", data, offset)
        chunk = data[offset + 8:offset + 8 + length]
        if kind == CHUNK_JSON:
            gltf = json.loads(chunk)
        elif kind == CHUNK_BIN:
            binary = chunk
        offset += 8 + length
    if gltf is None:
        raise ValueError(f"{path} has no JSON chunk")
    return gltf, binary


def write(path, gltf, binary) -> None:
    """Write a .glb: JSON chunk padded with spaces, BIN chunk padded with zeros (4-byte aligned),
    atomically (files.write_atomically)."""
    text = json.dumps(gltf, separators=(",", ":"), allow_nan=False).encode()
    text += b" " * (-len(text) % 4)
    binary = bytes(binary) + b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + (8 + len(binary) if binary else 0)

    def write_chunks(temp):
        with open(temp, "wb") as f:
            f.write(struct.pack("<III", GLB_MAGIC, 2, total))
            f.write(struct.pack("<II", len(text), CHUNK_JSON) + text)
            if binary:
                f.write(struct.pack("<II", len(binary), CHUNK_BIN) + binary)
    files.write_atomically(path, write_chunks)


def accessor_array(gltf, binary, index) -> np.ndarray:
    """(count, components) array of accessor ``index`` (tightly packed or strided; no sparse)."""
    acc = gltf["accessors"][index]
    view = gltf["bufferViews"][acc["bufferView"]]
    dtype = np.dtype(COMPONENT_DTYPES[acc["componentType"]])
    width = TYPE_SIZES[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    raw = np.frombuffer(binary, np.uint8, stride * (acc["count"] - 1) + dtype.itemsize * width, start)
    rows = np.lib.stride_tricks.as_strided(raw, (acc["count"], dtype.itemsize * width), (stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(acc["count"], width)


def index_colours(count: int) -> np.ndarray:
    """(count, 4) float32 colours encoding vertex indices: R, G = low and high 16 bits / 65535.
    The exporter's rounding (c * 65535 + 0.5, truncated) gives the bits back exactly."""
    i = np.arange(count, dtype=np.int64)
    out = np.zeros((count, 4), np.float32)
    out[:, 0] = (i & 0xFFFF) / INDEX_COLOUR_SCALE
    out[:, 1] = (i >> 16) / INDEX_COLOUR_SCALE
    out[:, 3] = 1.0
    return out


def vertex_indices(gltf, binary, mesh) -> list:
    """(attributes dict, Blender vertex of each file vertex) per primitive of ``mesh`` (a dict of
    gltf["meshes"]), from the :func:`index_colours` its COLOR_0 holds. Raises ValueError when a
    primitive has no COLOR_0."""
    out = []
    for primitive in mesh["primitives"]:
        attrs = primitive["attributes"]
        if "COLOR_0" not in attrs:
            raise ValueError(f"mesh '{mesh.get('name')}' was exported without COLOR_0")
        code = accessor_array(gltf, binary, attrs["COLOR_0"])
        if code.dtype.kind == "f":  # 3.4 writes float colours, later versions unsigned shorts
            code = np.rint(code.astype(np.float64) * INDEX_COLOUR_SCALE)
        code = code.astype(np.int64)
        out.append((attrs, code[:, 0] + (code[:, 1] << 16)))
    return out


def replace_vertex_channels(gltf, binary, channels_by_mesh: dict):
    """Rewrite the meshes named in ``channels_by_mesh`` (mesh name -> {layout channel: float32
    (Blender vertices, k)}, boxmarch/formats/layouts.py) whose COLOR_0 holds :func:`index_colours`: each
    channel becomes a float32 accessor of the values of the file vertices' Blender vertices
    ("COLOR" -> COLOR_0, "NORMAL", "TANGENT", "UVn" -> TEXCOORD_n), and the index COLOR_0 goes
    when the layout has no colour. Returns (gltf, binary) with unused buffer views dropped.
    Raises ValueError when a named mesh is missing or an index is out of range."""
    binary = bytearray(binary)
    found = set()
    for mesh in gltf.get("meshes", []):
        channels = channels_by_mesh.get(mesh.get("name"))
        if channels is None:
            continue
        vertex_count = len(next(iter(channels.values())))
        for attrs, index in vertex_indices(gltf, bytes(binary), mesh):
            attrs.pop("COLOR_0")
            if index.size and index.max() >= vertex_count:
                raise ValueError(f"mesh '{mesh['name']}': COLOR_0 holds vertex {index.max()}, "
                                 f"the mesh has {vertex_count}")
            for channel, per_vertex in channels.items():
                values = np.ascontiguousarray(per_vertex[index], np.float32)
                binary += b"\0" * (-len(binary) % 4)
                gltf["bufferViews"].append({"buffer": 0, "byteOffset": len(binary),
                                            "byteLength": values.nbytes, "target": ARRAY_BUFFER})
                binary += values.tobytes()
                gltf["accessors"].append({"bufferView": len(gltf["bufferViews"]) - 1, "componentType": FLOAT,
                                          "count": len(values), "type": f"VEC{values.shape[1]}"})
                attrs[GLTF_ATTRIBUTES.get(channel, channel.replace("UV", "TEXCOORD_"))] = len(gltf["accessors"]) - 1
        found.add(mesh.get("name"))
    missing = set(channels_by_mesh) - found
    if missing:
        raise ValueError(f"the exporter wrote no mesh named {sorted(missing)}")
    return _drop_unused(gltf, bytes(binary))


def _drop_unused(gltf, binary):
    """Remove accessors and buffer views nothing refers to, packing the buffer again."""
    used_accessors = set()
    for mesh in gltf.get("meshes", []):
        for primitive in mesh["primitives"]:
            used_accessors.update(primitive["attributes"].values())
            if "indices" in primitive:
                used_accessors.add(primitive["indices"])
            for target in primitive.get("targets", []):
                used_accessors.update(target.values())
    for skin in gltf.get("skins", []):
        if "inverseBindMatrices" in skin:
            used_accessors.add(skin["inverseBindMatrices"])
    for animation in gltf.get("animations", []):
        for sampler in animation.get("samplers", []):
            used_accessors.update((sampler["input"], sampler["output"]))
    accessor_map = {old: new for new, old in enumerate(sorted(used_accessors))}
    accessors = [gltf["accessors"][old] for old in sorted(used_accessors)]
    used_views = {a["bufferView"] for a in accessors if "bufferView" in a}
    used_views |= {image["bufferView"] for image in gltf.get("images", []) if "bufferView" in image}
    view_map, views, packed = {}, [], bytearray()
    for old in sorted(used_views):
        view = dict(gltf["bufferViews"][old])
        start = view.get("byteOffset", 0)
        packed += b"\0" * (-len(packed) % 4)
        chunk = binary[start:start + view["byteLength"]]
        view["byteOffset"] = len(packed)
        packed += chunk
        view_map[old] = len(views)
        views.append(view)
    for a in accessors:
        if "bufferView" in a:
            a["bufferView"] = view_map[a["bufferView"]]
    for image in gltf.get("images", []):
        if "bufferView" in image:
            image["bufferView"] = view_map[image["bufferView"]]
    for mesh in gltf.get("meshes", []):
        for primitive in mesh["primitives"]:
            primitive["attributes"] = {k: accessor_map[v] for k, v in primitive["attributes"].items()}
            if "indices" in primitive:
                primitive["indices"] = accessor_map[primitive["indices"]]
            if "targets" in primitive:
                primitive["targets"] = [{k: accessor_map[v] for k, v in t.items()} for t in primitive["targets"]]
    for skin in gltf.get("skins", []):
        if "inverseBindMatrices" in skin:
            skin["inverseBindMatrices"] = accessor_map[skin["inverseBindMatrices"]]
    for animation in gltf.get("animations", []):
        for sampler in animation.get("samplers", []):
            sampler["input"] = accessor_map[sampler["input"]]
            sampler["output"] = accessor_map[sampler["output"]]
    gltf["accessors"] = accessors
    gltf["bufferViews"] = views
    packed += b"\0" * (-len(packed) % 4)
    if gltf.get("buffers"):
        gltf["buffers"][0]["byteLength"] = len(packed)
    return gltf, bytes(packed)

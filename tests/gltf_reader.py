"""A small glTF binary reader for the tests, written from the glTF 2.0 specification and kept
apart from boxmarch's own export code (and from Blender's importer), so a round trip through it
checks the file, not the code that wrote it.

read_glb(path) -> list of meshes: {"name", "primitives": [{attribute name: float64 array}]},
with normalised integer attributes divided by their maximum as the spec says (section 3.11).
read_skin(path) -> the first skin's joints, inverse bind matrices and the node hierarchy."""
import json
import struct

import numpy as np

_COMPONENTS = {5120: ("b", 127.0), 5121: ("B", 255.0), 5122: ("h", 32767.0), 5123: ("H", 65535.0),
               5125: ("I", None), 5126: ("f", None)}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def chunks(data):
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2 and length == len(data), "not a glTF 2.0 binary"
    offset, chunks = 12, {}
    while offset < length:
        size, kind = struct.unpack_from("<I4s", data, offset)
        chunks[kind] = data[offset + 8:offset + 8 + size]
        offset += 8 + size
    return json.loads(chunks[b"JSON"]), chunks.get(b"BIN\0", b"")


def _accessor(doc, binary, index):
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    code, norm = _COMPONENTS[acc["componentType"]]
    width = _WIDTH[acc["type"]]
    item = struct.calcsize("<" + code)
    stride = view.get("byteStride") or item * width
    base = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    rows = [struct.unpack_from(f"<{width}{code}", binary, base + i * stride) for i in range(acc["count"])]
    values = np.array(rows, np.float64).reshape(acc["count"], width)
    if acc.get("normalized"):
        values = values / norm
    return values, acc


def read_glb(path):
    with open(path, "rb") as f:
        doc, binary = chunks(f.read())
    meshes = []
    for mesh in doc.get("meshes", []):
        primitives = []
        for primitive in mesh["primitives"]:
            attrs = {name: _accessor(doc, binary, i)[0] for name, i in primitive["attributes"].items()}
            attrs["_component_types"] = {name: doc["accessors"][i]["componentType"]
                                         for name, i in primitive["attributes"].items()}
            if "indices" in primitive:
                attrs["indices"] = _accessor(doc, binary, primitive["indices"])[0].astype(np.int64).reshape(-1)
            primitives.append(attrs)
        meshes.append({"name": mesh.get("name"), "primitives": primitives})
    return meshes


def node_matrix(node):
    """A node's local 4 x 4 transform: its column-major ``matrix`` or T * R * S (section 5.25)."""
    if "matrix" in node:
        return np.array(node["matrix"], np.float64).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
    rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = rotation * np.array(node.get("scale", [1.0, 1.0, 1.0]))
    m[:3, 3] = node.get("translation", [0.0, 0.0, 0.0])
    return m


def node_globals(local, parent):
    """(nodes, 4, 4) global transforms from local ones and each node's parent (-1: a root)."""
    out = [None] * len(local)

    def global_of(i):
        if out[i] is None:
            out[i] = local[i] if parent[i] < 0 else global_of(parent[i]) @ local[i]
        return out[i]

    return np.array([global_of(i) for i in range(len(local))])


def read_skin(path):
    """The file's first skin: {"joints": node indices, "inverse_bind": (joints, 4, 4),
    "node_names", "parent" (per node, -1 for roots), "local" and "global" (nodes, 4, 4) rest
    transforms}."""
    with open(path, "rb") as f:
        doc, binary = chunks(f.read())
    skin = doc["skins"][0]
    nodes = doc["nodes"]
    parent = np.full(len(nodes), -1)
    for i, node in enumerate(nodes):
        for child in node.get("children", []):
            parent[child] = i
    local = np.array([node_matrix(node) for node in nodes])
    inverse_bind = _accessor(doc, binary, skin["inverseBindMatrices"])[0].reshape(-1, 4, 4).transpose(0, 2, 1)
    return {"joints": list(skin["joints"]), "inverse_bind": inverse_bind, "parent": parent,
            "node_names": [node.get("name") for node in nodes], "local": local, "global": node_globals(local, parent)}

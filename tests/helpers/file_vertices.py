"""Vertices, triangles and bytes of an exported model, counted from the file alone (the tests'
own readers: tests/gltf_reader.py, tests/fbx_reader.py), never from the export code, for the
bytes-per-box test and benchmark (bench/bench_bytes.py).

A .glb's vertices are its accessors' counts (what every glTF loader uploads as they are). An
FBX file holds its data per polygon corner; an engine's importer welds corners whose every
attribute agrees (Unity's Weld Vertices, Unreal's build), so its vertices are the file's
distinct corner tuples (position, normal, tangent, binormal, every UV map and colour layer) and
each attribute is counted as float32 components, as the presets' import settings keep them.
flatten() gives boxes the per-corner normals a flat box has (Blender 3.4 to 5.0)."""
import numpy as np

from tests.gltf_reader import chunks

_COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def _accessor_item_bytes(accessor):
    return _COMPONENT_BYTES[accessor["componentType"]] * _WIDTH[accessor["type"]]


def glb_counts(path):
    """{"vertices", "vertex_bytes" (bytes of one vertex over all its attributes), "index_bytes"
    (all primitives' indices), "triangles", "attributes" (names), "file_bytes"} of a .glb
    (triangle-list primitives)."""
    with open(path, "rb") as f:
        data = f.read()
    doc, _binary = chunks(data)
    vertices = triangles = index_bytes = 0
    vertex_bytes, names = set(), set()
    for mesh in doc.get("meshes", []):
        for primitive in mesh["primitives"]:
            assert primitive.get("mode", 4) == 4, "triangle lists only"
            accessors = {name: doc["accessors"][i] for name, i in primitive["attributes"].items()}
            count = accessors["POSITION"]["count"]
            vertices += count
            vertex_bytes.add(sum(_accessor_item_bytes(a) for a in accessors.values()))
            names.update(accessors)
            indices = doc["accessors"][primitive["indices"]] if "indices" in primitive else None
            corners = indices["count"] if indices else count
            triangles += corners // 3
            index_bytes += corners * _accessor_item_bytes(indices) if indices else 0
    assert len(vertex_bytes) <= 1, "primitives with different attributes"
    return {"vertices": vertices, "vertex_bytes": vertex_bytes.pop() if vertex_bytes else 0,
            "index_bytes": index_bytes, "triangles": triangles, "attributes": sorted(names),
            "file_bytes": len(data)}


def fbx_counts(path):
    """The same figures of the first Geometry of an FBX file (needs ``bpy`` imported first):
    "vertices" are its distinct corner tuples (what an importer welds to), "vertex_bytes" their
    float32 components, "index_bytes" 4 per triangle corner (a 32-bit index buffer)."""
    from tests.fbx_reader import read_fbx_geometry

    raw = read_fbx_geometry(path)
    columns = [raw["position"]] + [raw[k] for k in ("normal", "tangent", "binormal") if k in raw]
    columns += [raw[name] for name in raw["uv_maps"] + raw["colours"]]
    corners = np.concatenate(columns, axis=1)
    with open(path, "rb") as f:
        file_bytes = len(f.read())
    triangles = len(raw["triangles"])
    return {"vertices": len(np.unique(corners, axis=0)), "vertex_bytes": 4 * corners.shape[1],
            "index_bytes": 4 * 3 * triangles, "triangles": triangles,
            "attributes": ["position"] + [k for k in ("normal", "tangent", "binormal") if k in raw]
            + raw["uv_maps"] + raw["colours"], "file_bytes": file_bytes}


def model_counts(path):
    """glb_counts or fbx_counts by the file's extension."""
    return glb_counts(path) if str(path).endswith(".glb") else fbx_counts(path)


def flatten(bpy, mesh):
    """Faces flat, every edge sharp, custom normals set to the face normals (Blender 5.0: "free"
    ones, which differ per corner on smooth faces too): as Add > Mesh > Cube and a normals
    modifier leave boxes, so every corner of a vertex has its own normal."""
    mesh.polygons.foreach_set("use_smooth", np.zeros(len(mesh.polygons), bool))
    mesh.edges.foreach_set("use_edge_sharp", np.ones(len(mesh.edges), bool))
    if hasattr(mesh, "use_auto_smooth"):
        mesh.use_auto_smooth = True
    face_normals = np.empty(len(mesh.polygons) * 3, np.float32)
    mesh.polygons.foreach_get("normal", face_normals)
    face_of_corner = np.repeat(np.arange(len(mesh.polygons)), [len(p.vertices) for p in mesh.polygons])
    corner_normals = face_normals.reshape(-1, 3)[face_of_corner]
    if bpy.app.version >= (5, 0, 0):
        mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "CORNER").data.foreach_set("vector", corner_normals.ravel())
    else:
        mesh.normals_split_custom_set(corner_normals)
    assert mesh.has_custom_normals

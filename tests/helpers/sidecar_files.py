"""A file read through its sidecar alone (docs/FORMAT.md): each channel found by the name the
sidecar's ``file_channels`` gives it, with the tests' own readers (tests/gltf_reader.py,
tests/fbx_reader.py) or Blender's library loader (.blend); shared by tests/test_sidecar.py (the
quantities) and tests/test_box_params_export.py (the box parameters)."""
import numpy as np

from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb


def file_channels(bpy, path, sidecar):
    """(positions (n, 3), {channel: (n, k) float64}) per vertex or corner of the file, by the
    names the sidecar gives; UV v read back as the engine reads it when the file flips it."""
    names = sidecar["file_channels"]
    if path.suffix == ".glb":
        (mesh,) = read_glb(path)
        prims = mesh["primitives"]
        cat = lambda key: np.concatenate([p[key] for p in prims])
        out = {channel: cat(name) for channel, name in names.items()}
        positions = cat("POSITION")
    elif path.suffix == ".fbx":
        raw = read_fbx_geometry(path)
        layers = {"LayerElementNormal": "normal", "LayerElementTangent": "tangent"}
        out = {channel: raw[layers.get(name, name)] for channel, name in names.items()}
        if "TANGENT" in out:  # FBX keeps the bitangent as its own layer
            out["BINORMAL"] = raw["binormal"]
        positions = raw["position"]
    else:
        with bpy.data.libraries.load(str(path)) as (src, dst):
            dst.meshes = list(src.meshes)
        (mesh,) = dst.meshes
        corner_vertex = np.empty(len(mesh.loops), np.int32)
        mesh.loops.foreach_get("vertex_index", corner_vertex)
        co = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        positions = co.reshape(-1, 3)[corner_vertex].astype(np.float64)
        out = {}
        for channel, name in names.items():
            if channel == "COLOR":
                colour = np.empty(len(mesh.vertices) * 4, np.float32)
                mesh.color_attributes[name].data.foreach_get("color", colour)
                out[channel] = colour.reshape(-1, 4)[corner_vertex].astype(np.float64)
            elif name.startswith("."):  # the bake's point attributes: one FLOAT2, or two INT joined by "+"
                out[channel] = np.stack([point_values(mesh, part) for part in name.split("+")], -1).reshape(
                    len(mesh.vertices), -1)[corner_vertex]
            else:
                uv = np.empty(len(mesh.loops) * 2, np.float32)
                mesh.uv_layers[name].data.foreach_get("uv", uv)
                out[channel] = uv.reshape(-1, 2).astype(np.float64)
    if sidecar["axes"]["v_flipped_in_file"]:
        for channel in out:
            if channel.startswith("UV"):
                out[channel][:, 1] = 1.0 - out[channel][:, 1]
    return positions, out


# docs/FORMAT.md: a bake stores these point attributes only where some box holds another value;
# absent, every vertex holds (value, components).
ABSENT_POINT_ATTRIBUTES = {".boxmarch_shape_material": (0.0, 2), ".boxmarch_parent": (-1.0, 1),
                           ".boxmarch_depth": (0.0, 1)}


def point_values(mesh, name):
    """float64 (vertices,) or (vertices, 2) of a point attribute of a Blender mesh (one the bake
    left out: its documented default)."""
    if name not in mesh.attributes and name in ABSENT_POINT_ATTRIBUTES:
        value, width = ABSENT_POINT_ATTRIBUTES[name]
        values = np.full((len(mesh.vertices), width), value)
        return values[:, 0] if width == 1 else values
    attribute = mesh.attributes[name]
    assert attribute.domain == "POINT", (name, attribute.domain)
    width = 2 if attribute.data_type == "FLOAT2" else 1
    data = np.empty(len(mesh.vertices) * width, np.float64)
    attribute.data.foreach_get("vector" if width == 2 else "value", data)
    return data.reshape(len(mesh.vertices), -1).squeeze(-1) if width == 1 else data.reshape(-1, 2)


def values(channels, specs):
    """(n, len(specs)) of channel components named like "UV3.x", "COLOR.a", "TABLE.r"."""
    component = {"x": 0, "y": 1, "r": 0, "g": 1, "b": 2, "a": 3}
    return np.stack([channels[s.split(".")[0]][:, component[s.split(".")[1]]] for s in specs], 1)

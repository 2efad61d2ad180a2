"""Engine layouts: which vertex channels carry a box's frame, offset, half-extents and index.

Blender-free (format-facing). Every layout is computed from one set of per-vertex quantities in
the target engine's object frame (:class:`BoxData`), and every layout carries all of them except
CLASSIC, the blog's layout, kept so its shader decodes unchanged. docs/ENGINES.md measures each
layout against each engine's importer; docs/FORMAT.md states the decode of each.

Channels (per vertex unless noted; UVn = the n-th UV map / TEXCOORD_n, UV0 stays the artist's):

=============  ==================================================================================
CLASSIC        COLOR = (0.5 + 0.5 s f, s); UV1 = q.xy; UV2 = q.zw;
               UV3 = (shape, material); UV4 = (random, user); UV5 = (parent, depth)
UV_FRAME       UV1 = q.xy; UV2 = q.zw (where CLASSIC has them); UV3 = f.xy; UV4 = (f.z, index);
               UV5 = h.xy; UV6 = (h.z, parent); UV7 = (shape, material); random, user and depth
               in the box table only
NORMAL_FRAME   NORMAL = x_z; TANGENT = (x_x, 1); UV1 = f.xy; UV2 = (f.z, index); UV3 = h.xy;
               UV4 = (h.z, 0); UV5 = (shape, material); UV6 = (random, user); UV7 = (parent, depth)
NORMAL_COLOR   NORMAL = x_z; TANGENT = (x_x, 1); COLOR = (f, index); TABLE[index] = (h, parent), a
               float texture one texel per box (UV2 stays free for lightmaps), with four more planes:
               (shape, material, random, user), (depth, 0, 0, 0), (origin, 0), q
=============  ==================================================================================

q: the box frame as a unit quaternion (x, y, z, w), box-local to object; x_x, x_z: the frame's
local x and z axes in object space (the NORMAL_* layouts carry the frame in the two vectors every
engine's skinning transforms; the local y axis is cross(NORMAL, TANGENT.xyz) * TANGENT.w, the
glTF bitangent); f: vertex to box origin in box-local coordinates; h: half-extents about the
origin (largest |f| per local axis over the box); index: the box's number, 0 .. boxes - 1;
shape, material, random, user: the box's four parameters (core.PARAM_NAMES); parent: the parent
box's number (-1: a root), depth: 0 at a root. The box table (:func:`box_table`, every layout
with an index) holds, per box, (h, parent), (shape, material, random, user), (depth, 0, 0, 0),
(origin, 0) and q (object space).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

QUAT_XY_UV = "BoxQuatXY"  # the bake's UV maps of the frame's quaternion (mesh_io), CLASSIC's UV1 and UV2
QUAT_ZW_UV = "BoxQuatZW"
_FRAME_QUATERNION = {"encoding": "quaternion_xyzw", "channels": ["UV1.x", "UV1.y", "UV2.x", "UV2.y"]}
_FRAME_NORMAL_TANGENT = {"encoding": "normal_tangent", "channels": ["NORMAL", "TANGENT"]}
# FBX UV map names by what the channel holds (glTF files number the channels instead).
_OFFSET_HALF_UV_NAMES = ("BoxOffsetXY", "BoxOffsetZIndex", "BoxHalfXY", "BoxHalfZ")
_PARAM_UV_NAMES = {("shape", "material"): "BoxShapeMaterial", ("random", "user"): "BoxRandomUser",
                  ("parent", "depth"): "BoxParentDepth"}
_ALL_PARAMS = {"shape_material": ("shape", "material"), "random_user": ("random", "user"),
               "parent_depth": ("parent", "depth")}


@dataclass(frozen=True)
class Layout:
    """Everything the add-on knows about one layout but its encode (:func:`channels`) and its
    decodes (:func:`to_origin`, shaders/glsl/preview.vert.glsl's ``BM_LAYOUT_<name>`` branch)."""

    name: str
    label: str
    description: str
    channels: tuple[str, ...]   # per-vertex channels in the order written ("COLOR", "NORMAL", "TANGENT", "UVn")
    uv_names: tuple[str, ...]   # FBX UV map name of UV1, UV2, ... (UV0 stays the artist's)
    quantities: dict            # quantity -> {"encoding", "channels"}: the sidecar's "quantities"
    param_channels: dict        # "UVn" -> the pair of box values it holds (the rest in the box table)
    skin_safe: bool             # the frame rides in NORMAL + TANGENT (FBX: the tangent-space patch)
    table_format: str = ""      # the box table's file beside the model (sidecar "box_table" format; "": none)
    parent_channel: str = ""    # a float channel's free component holding the parent's number ("UV6.y")

    @property
    def uv_channels(self) -> int:
        """UV maps after the artist's UV0."""
        return len(self.uv_names)

    @property
    def has_index(self) -> bool:
        """Whether the layout numbers its boxes across the file (else each mesh from 0, no index stored)."""
        return "index" in self.quantities

    @property
    def has_table(self) -> bool:
        """Whether the layout writes the box table (:func:`box_table`)."""
        return bool(self.table_format)

    @property
    def offset_in_uvs(self) -> bool:
        """Whether the offset rides in float UV maps (an importer's half-float UVs round it)."""
        return self.quantities["offset"]["channels"][0].startswith("UV")

    @property
    def classic_colour(self) -> bool:
        """Whether the offset rides in the CLASSIC colour (an 8-bit colour clips its alpha above 1)."""
        return self.quantities["offset"]["encoding"] == "classic_colour"

    @property
    def half_extents_per_vertex(self) -> bool:
        """Whether a vertex channel holds the box's half-extents (else none or the box table)."""
        return self.quantities.get("half_extents", {}).get("encoding") == "float"

    def uv_name(self, channel: str) -> str:
        """The FBX UV map name of this layout's channel "UVn"."""
        return self.uv_names[int(channel[2:]) - 1]


def _params(*uvs: str, names=("shape_material", "random_user", "parent_depth")) -> dict:
    return {uv: _ALL_PARAMS[name] for uv, name in zip(uvs, names)}


def _floats(offset: str, index: str, half: str) -> dict:
    """The offset, index and half-extents quantities as float channels (``offset``: "UVa.x UVa.y UVb.x")."""
    return {"offset": {"encoding": "float", "channels": offset.split()},
            "index": {"encoding": "float", "channels": [index]},
            "half_extents": {"encoding": "float", "channels": half.split()}}


def _layout(name, label, description, channels, quantities, param_channels, skin_safe, uv_names=(),
            table="float32_rgba", parent=""):
    uv_names = tuple(uv_names) + tuple(_PARAM_UV_NAMES[param_channels[f"UV{n}"]]
                                       for n in range(len(uv_names) + 1, len(channels) + 1) if f"UV{n}" in param_channels)
    return Layout(name, label, description, tuple(channels), uv_names, quantities, param_channels, skin_safe,
                  table, parent)


_UVS = tuple(f"UV{n}" for n in range(1, 8))
LAYOUTS = {layout.name: layout for layout in (
    _layout("CLASSIC", "Classic (colour + 5 UVs)", "The blog's layout: offset in the colour, quaternion in UV1-2, "
            "box parameters and parent in UV3-5; no half-extents or index", ("COLOR", *_UVS[:5]),
            {"frame": _FRAME_QUATERNION,
             "offset": {"encoding": "classic_colour", "channels": ["COLOR.r", "COLOR.g", "COLOR.b", "COLOR.a"]}},
            _params("UV3", "UV4", "UV5"), False, (QUAT_XY_UV, QUAT_ZW_UV), table=""),
    _layout("UV_FRAME", "Float UVs (7 UVs)", "Quaternion, offset, index, half-extents and parent in float UV1-6, "
            "shape and material in UV7 (the rest of the parameters in the box table)", _UVS,
            {"frame": _FRAME_QUATERNION, **_floats("UV3.x UV3.y UV4.x", "UV4.y", "UV5.x UV5.y UV6.x")},
            _params("UV7"), False, (QUAT_XY_UV, QUAT_ZW_UV, *_OFFSET_HALF_UV_NAMES), parent="UV6.y"),
    _layout("NORMAL_FRAME", "Normal + tangent frame (7 UVs)", "Frame in NORMAL + TANGENT (skinning carries it); "
            "offset, index and half-extents in float UV1-4, box parameters and parent in UV5-7",
            ("NORMAL", "TANGENT", *_UVS),
            {"frame": _FRAME_NORMAL_TANGENT, **_floats("UV1.x UV1.y UV2.x", "UV2.y", "UV3.x UV3.y UV4.x")},
            _params("UV5", "UV6", "UV7"), True, _OFFSET_HALF_UV_NAMES),
    _layout("NORMAL_COLOR", "Normal + tangent frame, colour, box table", "Frame in NORMAL + TANGENT, offset and "
            "index in a float colour, half-extents, parent and box parameters in a float texture by index "
            "(UV2 left free)", ("NORMAL", "TANGENT", "COLOR"),
            {"frame": _FRAME_NORMAL_TANGENT, "offset": {"encoding": "float", "channels": ["COLOR.r", "COLOR.g", "COLOR.b"]},
             "index": {"encoding": "float", "channels": ["COLOR.a"]},
             "half_extents": {"encoding": "box_table", "channels": ["TABLE.r", "TABLE.g", "TABLE.b"]}},
            {}, True, table="godot3_tres"),
)}


def layout_named(name: str) -> Layout:
    """The layout called ``name``, or a clear ValueError naming the layouts there are."""
    if name not in LAYOUTS:
        raise ValueError(f"layout must be one of {sorted(LAYOUTS)}, got {name!r}")
    return LAYOUTS[name]


# The UV channels holding only box parameters and parents, per layout (Layout.param_channels).
PARAM_CHANNELS = {name: layout.param_channels for name, layout in LAYOUTS.items()}


@dataclass
class BoxData:
    """Per-vertex box data in the target's object frame (float64 unless noted)."""

    quaternions: np.ndarray   # (n, 4) unit, box-local to object
    offsets: np.ndarray       # (n, 3) f, box-local
    half_extents: np.ndarray  # (n, 3) h of the vertex's box
    index: np.ndarray         # (n,) int64 box number
    classic_rgba: np.ndarray  # (n, 4) float32 the CLASSIC colour as the shader reads it
    box_half_extents: np.ndarray  # (boxes, 3) h by box number (the NORMAL_COLOR table)
    box_params: np.ndarray | None = None  # (boxes, 4) shape, material, random, user (None: zeros)
    box_parent: np.ndarray | None = None  # (boxes,) parent's box number, -1 for a root (None: all roots)
    box_depth: np.ndarray | None = None   # (boxes,) 0 at a root (None: zeros)
    box_origins: np.ndarray | None = None  # (boxes, 3) object-space origins (None: zeros)
    box_quaternions: np.ndarray | None = None  # (boxes, 4) frames, x, y, z, w (None: identity)
    index_base: int = 0                   # box number of this mesh's first box (index - index_base: row)

    def box_values(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(params (boxes, 4), parent (boxes,), depth (boxes,)) as float64, defaults filled in."""
        boxes = len(self.box_half_extents)
        params = np.zeros((boxes, 4)) if self.box_params is None else np.asarray(self.box_params, np.float64)
        parent = np.full(boxes, -1.0) if self.box_parent is None else np.asarray(self.box_parent, np.float64)
        depth = np.zeros(boxes) if self.box_depth is None else np.asarray(self.box_depth, np.float64)
        return params, parent, depth


def quaternion_matrices(q) -> np.ndarray:
    """float64 (n, 3, 3) rotation matrices R(q) of unit quaternions q (n, 4) as (x, y, z, w):
    column i is R(q) e_i, the box's local axis i (the frame every layout encodes)."""
    x, y, z, w = np.asarray(q, np.float64).reshape(-1, 4).T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], 1)


# What the r, g, b, a of each texel a box has in the box table hold (None: 0), plane by plane: the
# one statement of the table's layout, which box_table fills and the sidecar records.
TABLE_PLANE_CONTENTS = [["half_extents.x", "half_extents.y", "half_extents.z", "parent"],
                        ["shape", "material", "random", "user"], ["depth", None, None, None],
                        ["origin.x", "origin.y", "origin.z", None], ["frame.x", "frame.y", "frame.z", "frame.w"]]
TABLE_PLANES = len(TABLE_PLANE_CONTENTS)  # texels per box in the box table


def box_table(data: BoxData) -> np.ndarray:
    """float32 (boxes, TABLE_PLANES, 4): per box (h, parent), (shape, material, random, user),
    (depth, 0, 0, 0), (origin, 0) and the frame's quaternion, so a shader reaches its parent's
    frame, size and parameters by the parent's number."""
    params, parent, depth = data.box_values()
    table = np.zeros((len(params), TABLE_PLANES, 4))
    table[:, 0, :3] = data.box_half_extents
    table[:, 0, 3] = parent
    table[:, 1] = params
    table[:, 2, 0] = depth
    if data.box_origins is not None:
        table[:, 3, :3] = data.box_origins
    table[:, 4] = [0.0, 0.0, 0.0, 1.0] if data.box_quaternions is None else data.box_quaternions
    return table.astype(np.float32)


def channels(layout: str, data: BoxData) -> dict[str, np.ndarray]:
    """float32 arrays by channel name ("COLOR", "NORMAL", "TANGENT", "UV1".."UV7": per vertex,
    in the order of Layout.channels; "TABLE": the box table, :func:`box_table`, every layout with
    an index) that ``layout`` writes for ``data``."""
    spec = layout_named(layout)
    n = len(data.index)
    q, f, h = data.quaternions, data.offsets, data.half_extents
    index = data.index.astype(np.float64)
    pair = lambda a, b: np.stack([a, b], 1).astype(np.float32)
    params, parent, depth = data.box_values()
    row = data.index - data.index_base
    p = params[row]
    values = {"shape": p[:, 0], "material": p[:, 1], "random": p[:, 2], "user": p[:, 3],
              "parent": parent[row], "depth": depth[row]}
    last = values["parent"] if spec.parent_channel else np.zeros(n)  # the parent in the last float channel's free half
    out = {uv: pair(*(values[name] for name in names)) for uv, names in spec.param_channels.items()}
    if spec.skin_safe:
        frames = quaternion_matrices(q)
        axis_x, axis_z = frames[:, :, 0], frames[:, :, 2]
        out["NORMAL"] = axis_z.astype(np.float32)
        out["TANGENT"] = np.concatenate([axis_x, np.ones((n, 1))], 1).astype(np.float32)
    else:
        out["UV1"], out["UV2"] = pair(q[:, 0], q[:, 1]), pair(q[:, 2], q[:, 3])
    offset = spec.quantities["offset"]
    if spec.classic_colour:
        out["COLOR"] = np.asarray(data.classic_rgba, np.float32)
    elif offset["channels"][0].startswith("COLOR"):
        out["COLOR"] = np.concatenate([f, index[:, None]], 1).astype(np.float32)
    else:  # offset, index and half-extents in four float UV pairs from the offset's first
        first = int(offset["channels"][0].split(".")[0][2:])
        payload = [pair(f[:, 0], f[:, 1]), pair(f[:, 2], index), pair(h[:, 0], h[:, 1]), pair(h[:, 2], last)]
        out.update({f"UV{first + i}": values for i, values in enumerate(payload)})
    out = {name: out[name] for name in spec.channels}
    if spec.has_table:
        out["TABLE"] = box_table(data)
    return out


def component(channels: dict, name: str) -> np.ndarray:
    """The values of one component of ``channels``, named as in Layout.quantities ("UV4.y", "COLOR.a")."""
    channel, letter = name.split(".")
    return np.asarray(channels[channel])[:, "xyzw".index(letter) if letter in "xyzw" else "rgba".index(letter)]


def to_origin(layout: str, channels: dict) -> np.ndarray:
    """(n, 3) float64 object-space vectors from each vertex to its box origin, decoded from
    ``channels`` as docs/ENGINES.md (docs/FORMAT.md for CLASSIC) states for ``layout``."""
    spec = layout_named(layout)
    c = {k: np.asarray(v, np.float64) for k, v in channels.items() if k != "TABLE"}
    offset = spec.quantities["offset"]
    if spec.classic_colour:
        f = (c["COLOR"][:, :3] * 2.0 - 1.0) / c["COLOR"][:, 3:]
    else:
        f = np.stack([component(c, name) for name in offset["channels"]], 1)
    if spec.skin_safe:
        x, z = c["TANGENT"][:, :3], c["NORMAL"]
        return x * f[:, :1] + np.cross(z, x) * c["TANGENT"][:, 3:] * f[:, 1:2] + z * f[:, 2:]
    q = np.concatenate([c["UV1"], c["UV2"]], 1)
    u = q[:, :3]
    return f + 2.0 * np.cross(u, np.cross(u, f) + q[:, 3:] * f)


def with_half_float_uvs(channels: dict, half_float_uvs, flip_v: bool) -> dict:
    """``channels`` as an importer holds them when it stores the UV channels ``half_float_uvs``
    (numbers n of "UVn") as half floats, rounded to nearest (v read as 1 - v first when
    ``flip_v``, as the file then holds it): Unity's vertex compression, Unreal's default UVs."""
    stored = dict(channels)
    for n in half_float_uvs:
        uv = np.array(channels[f"UV{n}"], np.float32)
        if flip_v:
            uv[:, 1] = np.float32(1.0) - uv[:, 1]
        uv = uv.astype(np.float16).astype(np.float32)
        if flip_v:
            uv[:, 1] = np.float32(1.0) - uv[:, 1]
        stored[f"UV{n}"] = uv
    return stored


def with_godot3_compression(channels: dict) -> dict:
    """``channels`` as Godot 3.2's glTF import holds them with mesh compression on (its
    default), as measured by tests/test_engines_smoke.py: colour 8-bit unorm, truncated and
    clamped to [0, 1]; normal and tangent 8-bit snorm, truncated."""
    stored = dict(channels)
    if "COLOR" in channels:
        stored["COLOR"] = np.clip(np.floor(np.asarray(channels["COLOR"], np.float32) * np.float32(255))
                                  / np.float32(255), 0.0, 1.0)
    for name in ("NORMAL", "TANGENT"):
        if name in channels:
            stored[name] = np.trunc(np.asarray(channels[name], np.float32) * np.float32(127)) / np.float32(127)
    return stored


def import_error(layout: str, channels: dict, stored: dict, half_extents) -> float:
    """Worst decode error, over the largest half-extent ``half_extents`` (n, 3) of the vertex's
    box, of the channels an importer ``stored`` against the exported ``channels``."""
    miss = np.linalg.norm(to_origin(layout, stored) - to_origin(layout, channels), axis=1)
    reach = np.maximum(np.abs(np.asarray(half_extents, np.float64)).max(axis=1), 1e-30) if len(miss) else 1.0
    return float((miss / reach).max()) if len(miss) else 0.0

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


@dataclass(frozen=True)
class Layout:
    name: str
    label: str
    description: str
    uv_channels: int        # UV maps after the artist's UV0
    skin_safe: bool         # the frame rides in NORMAL + TANGENT


LAYOUTS = {layout.name: layout for layout in (
    Layout("CLASSIC", "Classic (colour + 5 UVs)", "The blog's layout: offset in the colour, quaternion in UV1-2, "
           "box parameters and parent in UV3-5; no half-extents or index", 5, False),
    Layout("UV_FRAME", "Float UVs (7 UVs)", "Quaternion, offset, index, half-extents and parent in float UV1-6, "
           "shape and material in UV7 (the rest of the parameters in the box table)", 7, False),
    Layout("NORMAL_FRAME", "Normal + tangent frame (7 UVs)", "Frame in NORMAL + TANGENT (skinning carries it); "
           "offset, index and half-extents in float UV1-4, box parameters and parent in UV5-7", 7, True),
    Layout("NORMAL_COLOR", "Normal + tangent frame, colour, box table", "Frame in NORMAL + TANGENT, offset and "
           "index in a float colour, half-extents, parent and box parameters in a float texture by index "
           "(UV2 left free)", 0, True),
)}


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


TABLE_PLANES = 5  # texels per box in the box table
# Per layout, the UV channels holding only box parameters and parents (by their pair of values).
PARAM_CHANNELS = {
    "CLASSIC": {"UV3": ("shape", "material"), "UV4": ("random", "user"), "UV5": ("parent", "depth")},
    "UV_FRAME": {"UV7": ("shape", "material")},
    "NORMAL_FRAME": {"UV5": ("shape", "material"), "UV6": ("random", "user"), "UV7": ("parent", "depth")},
    "NORMAL_COLOR": {},
}


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
    """float32 arrays by channel name ("COLOR", "NORMAL", "TANGENT", "UV1".."UV6": per vertex;
    "TABLE": the box table, :func:`box_table`, every layout with an index) that ``layout`` writes
    for ``data``."""
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {sorted(LAYOUTS)}, got {layout!r}")
    n = len(data.index)
    q, f, h = data.quaternions, data.offsets, data.half_extents
    index = data.index.astype(np.float64)
    zero = np.zeros(n)
    pair = lambda a, b: np.stack([a, b], 1).astype(np.float32)
    params, parent, depth = data.box_values()
    row = data.index - data.index_base
    p, up, d = params[row], parent[row], depth[row]
    shape_material, random_user, parent_depth = pair(p[:, 0], p[:, 1]), pair(p[:, 2], p[:, 3]), pair(up, d)
    last = up if layout == "UV_FRAME" else zero  # UV_FRAME's parent rides in its last frame channel's free half
    payload = [pair(f[:, 0], f[:, 1]), pair(f[:, 2], index), pair(h[:, 0], h[:, 1]), pair(h[:, 2], last)]
    out = {}
    if layout == "CLASSIC":
        out["COLOR"] = np.asarray(data.classic_rgba, np.float32)
    if layout in ("CLASSIC", "UV_FRAME"):
        out["UV1"], out["UV2"] = pair(q[:, 0], q[:, 1]), pair(q[:, 2], q[:, 3])
    if layout == "CLASSIC":
        out.update(UV3=shape_material, UV4=random_user, UV5=parent_depth)
    if layout == "UV_FRAME":
        out.update({f"UV{3 + i}": values for i, values in enumerate(payload)})
        out["UV7"] = shape_material
    if layout in ("NORMAL_FRAME", "NORMAL_COLOR"):
        frames = quaternion_matrices(q)
        axis_x, axis_z = frames[:, :, 0], frames[:, :, 2]
        out["NORMAL"] = axis_z.astype(np.float32)
        out["TANGENT"] = np.concatenate([axis_x, np.ones((n, 1))], 1).astype(np.float32)
    if layout == "NORMAL_FRAME":
        out.update({f"UV{1 + i}": values for i, values in enumerate(payload)})
        out.update(UV5=shape_material, UV6=random_user, UV7=parent_depth)
    if layout == "NORMAL_COLOR":
        out["COLOR"] = np.concatenate([f, index[:, None]], 1).astype(np.float32)
    if layout != "CLASSIC":
        out["TABLE"] = box_table(data)
    return out


def to_origin(layout: str, channels: dict) -> np.ndarray:
    """(n, 3) float64 object-space vectors from each vertex to its box origin, decoded from
    ``channels`` as docs/ENGINES.md (docs/FORMAT.md for CLASSIC) states for ``layout``."""
    c = {k: np.asarray(v, np.float64) for k, v in channels.items() if k != "TABLE"}
    if layout in ("UV_FRAME", "CLASSIC"):
        q = np.concatenate([c["UV1"], c["UV2"]], 1)
        if layout == "UV_FRAME":
            f = np.concatenate([c["UV3"], c["UV4"][:, :1]], 1)
        else:
            f = (c["COLOR"][:, :3] * 2.0 - 1.0) / c["COLOR"][:, 3:]
        u = q[:, :3]
        return f + 2.0 * np.cross(u, np.cross(u, f) + q[:, 3:] * f)
    if layout in ("NORMAL_FRAME", "NORMAL_COLOR"):
        x, z = c["TANGENT"][:, :3], c["NORMAL"]
        f = np.concatenate([c["UV1"], c["UV2"][:, :1]], 1) if layout == "NORMAL_FRAME" else c["COLOR"][:, :3]
        return x * f[:, :1] + np.cross(z, x) * c["TANGENT"][:, 3:] * f[:, 1:2] + z * f[:, 2:]
    raise ValueError(f"layout must be one of {sorted(LAYOUTS)}, got {layout!r}")


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

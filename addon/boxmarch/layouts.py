"""Engine layouts: which vertex channels carry a box's frame, offset, half-extents and index.

Blender-free (format-facing). Every layout is computed from one set of per-vertex quantities in
the target engine's object frame (:class:`BoxData`), and every layout carries all of them except
CLASSIC, the blog's layout, kept so its shader decodes unchanged. docs/ENGINES.md measures each
layout against each engine's importer; docs/FORMAT.md states the decode of each.

Channels (per vertex unless noted; UVn = the n-th UV map / TEXCOORD_n, UV0 stays the artist's):

=============  ==================================================================================
CLASSIC        COLOR = (0.5 + 0.5 s f, s); UV1 = q.xy; UV2 = q.zw
UV_FRAME       UV1 = q.xy; UV2 = q.zw (where CLASSIC has them); UV3 = f.xy; UV4 = (f.z, index);
               UV5 = h.xy; UV6 = (h.z, 0)
NORMAL_FRAME   NORMAL = x_z; TANGENT = (x_x, 1); UV1 = f.xy; UV2 = (f.z, index); UV3 = h.xy;
               UV4 = (h.z, 0)
NORMAL_COLOR   NORMAL = x_z; TANGENT = (x_x, 1); COLOR = (f, index); TABLE[index] = (h, 0), a
               float texture one texel per box (UV2 stays free for lightmaps)
=============  ==================================================================================

q: the box frame as a unit quaternion (x, y, z, w), box-local to object; x_x, x_z: the frame's
local x and z axes in object space (the NORMAL_* layouts carry the frame in the two vectors every
engine's skinning transforms; the local y axis is cross(NORMAL, TANGENT.xyz) * TANGENT.w, the
glTF bitangent); f: vertex to box origin in box-local coordinates; h: half-extents about the
origin (largest |f| per local axis over the box); index: the box's number, 0 .. boxes - 1.
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
    Layout("CLASSIC", "Classic (colour + 2 UVs)", "The blog's layout: offset in the colour, quaternion in UV1-2; "
           "no half-extents or index", 2, False),
    Layout("UV_FRAME", "Float UVs (6 UVs)", "Quaternion, offset, index and half-extents in float UV1-6", 6, False),
    Layout("NORMAL_FRAME", "Normal + tangent frame (4 UVs)", "Frame in NORMAL + TANGENT (skinning carries it); "
           "offset, index and half-extents in float UV1-4", 4, True),
    Layout("NORMAL_COLOR", "Normal + tangent frame, colour, box table", "Frame in NORMAL + TANGENT, offset and "
           "index in a float colour, half-extents in a float texture by index (UV2 left free)", 0, True),
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


def frame_axes(q) -> tuple[np.ndarray, np.ndarray]:
    """(x axis, z axis) of the frames of unit quaternions q (n, 4): R(q) e_x and R(q) e_z."""
    q = np.asarray(q, np.float64).reshape(-1, 4)
    x, y, z, w = q.T
    axis_x = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], 1)
    axis_z = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], 1)
    return axis_x, axis_z


def channels(layout: str, data: BoxData) -> dict[str, np.ndarray]:
    """float32 arrays by channel name ("COLOR", "NORMAL", "TANGENT", "UV1".."UV6": per vertex;
    "TABLE": per box, RGBA) that ``layout`` writes for ``data``."""
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {sorted(LAYOUTS)}, got {layout!r}")
    n = len(data.index)
    q, f, h = data.quaternions, data.offsets, data.half_extents
    index = data.index.astype(np.float64)
    zero = np.zeros(n)
    pair = lambda a, b: np.stack([a, b], 1).astype(np.float32)
    payload = [pair(f[:, 0], f[:, 1]), pair(f[:, 2], index), pair(h[:, 0], h[:, 1]), pair(h[:, 2], zero)]
    out = {}
    if layout == "CLASSIC":
        out["COLOR"] = np.asarray(data.classic_rgba, np.float32)
    if layout in ("CLASSIC", "UV_FRAME"):
        out["UV1"], out["UV2"] = pair(q[:, 0], q[:, 1]), pair(q[:, 2], q[:, 3])
    if layout == "UV_FRAME":
        out.update({f"UV{3 + i}": values for i, values in enumerate(payload)})
    if layout in ("NORMAL_FRAME", "NORMAL_COLOR"):
        axis_x, axis_z = frame_axes(q)
        out["NORMAL"] = axis_z.astype(np.float32)
        out["TANGENT"] = np.concatenate([axis_x, np.ones((n, 1))], 1).astype(np.float32)
    if layout == "NORMAL_FRAME":
        out.update({f"UV{1 + i}": values for i, values in enumerate(payload)})
    if layout == "NORMAL_COLOR":
        out["COLOR"] = np.concatenate([f, index[:, None]], 1).astype(np.float32)
        table = np.zeros((len(data.box_half_extents), 4))
        table[:, :3] = data.box_half_extents
        out["TABLE"] = table.astype(np.float32)
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

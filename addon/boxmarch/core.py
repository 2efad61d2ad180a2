"""Blender-free NumPy API of boxmarch.

Everything here takes and returns NumPy arrays; nothing imports ``bpy``. The heavy work runs in
the native module ``boxmarch._core`` with the GIL released, on private copies of the input arrays
(another thread writing them during a call cannot change what was checked).

Mesh arrays (the layout Blender uses):

* ``positions``: float32 (N, 3)
* ``edges``: int32 (E, 2) vertex pairs
* ``face_starts``, ``face_sizes``: int32 (F,): face f owns corners
  ``face_starts[f] .. face_starts[f] + face_sizes[f] - 1``
* ``corner_verts``: int32 (C,) the vertex of each corner

The baked data and its decode are documented in docs/FORMAT.md. The submesh tools' functions live
in core_tools.py, the per-box parameters and hierarchy in core_boxes.py, the reference raymarcher
and renderer in core_render.py; all three are part of this API (imported here), and none of them
imports this module.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .core_tools import (  # noqa: F401 (re-exported: the submesh tools are part of this API)
    find_close_pairs, find_duplicate_submeshes, merge_passes, merge_targets, pack_uv_by_height, remove_vertices,
    select_linked_across, select_linked_submeshes, weld)
from .core_boxes import (  # noqa: F401 (re-exported: per-box parameters and hierarchy are part of this API)
    HIERARCHY_RULES, PARAM_NAMES, box_fingerprints, box_hierarchy, box_random, dominant_per_submesh, nearest_rows,
    parents_by_bone, reduce_per_submesh)
from .core_render import (  # noqa: F401 (re-exported: the reference renderer is part of this API)
    NORMAL_RULES, SDF_PRESETS, MarchResult, RenderResult, front_to_back, occluder_boxes, preset_of_shape, raymarch,
    render_boxes, render_boxes_by_shape, sdf_distance)
from .native import _core, checked_indices, checked_int, checked_mask, row_count

ORIGIN_MODES = ("BOUNDS", "MEAN")
ENCODINGS = ("FLOAT_COLOR", "BYTE_COLOR")
FRAME_SOURCES = ("FACES", "FACE_EDGE", "EDGES", "ONE_AXIS", "IDENTITY")
STATUS_BAKED, STATUS_UNCHANGED, STATUS_NOT_SELECTED = 0, 1, 2
# Radians; the core's own bounds (boxmarch.h kAngleEpsilonMin/Max), read by the bake operator's
# property limits and the command line.
ANGLE_EPSILON_RANGE = (_core.ANGLE_EPSILON_MIN, _core.ANGLE_EPSILON_MAX)
ANGLE_EPSILON_DEFAULT = _core.ANGLE_EPSILON_DEFAULT  # BakeOptions' default, the one statement of it
# The bake's seeds of the per-box random value: 0..RANDOM_SEED_MAX, for the operator's Random Seed
# (a Blender IntProperty holds int32), the command line's --random-seed and mesh_io.prepare_bake.
RANDOM_SEED_MAX = 2**31 - 1


@dataclass
class BakeResult:
    """What :func:`bake` computed.

    Per vertex: ``submesh_of_vertex`` (int32), ``fingerprints`` (uint32), ``offsets`` (float32
    RGBA, or uint8 RGBA for BYTE_COLOR). Per submesh: ``quaternions`` (float32 x, y, z, w),
    ``origins`` (float64 object space), ``half_extents`` (float64, local axes), ``scales``
    (float32 alpha), ``sources`` (index into FRAME_SOURCES), ``statuses`` (STATUS_*).
    Entries of submeshes that were not baked are zero, with source ``IDENTITY``.
    """

    submesh_of_vertex: np.ndarray
    fingerprints: np.ndarray
    offsets: np.ndarray
    quaternions: np.ndarray
    origins: np.ndarray
    half_extents: np.ndarray
    scales: np.ndarray
    sources: np.ndarray
    statuses: np.ndarray
    submesh_count: int
    baked: int
    cache_hits: int
    unchanged: int
    not_selected: int
    degenerate: int
    max_error: float
    max_relative_error: float
    extra: dict = field(default_factory=dict)

    @property
    def written(self) -> np.ndarray:
        """uint8 per submesh: 1 where this bake wrote new values."""
        return (self.statuses == STATUS_BAKED).astype(np.uint8)


def bake(positions, edges, face_starts, face_sizes, corner_verts, *, mask=None,
         previous_fingerprints=None, offsets=None, angle_epsilon=ANGLE_EPSILON_DEFAULT, origin="BOUNDS",
         sort_axes_by_extent=False, axis_turn=0, encoding="FLOAT_COLOR", use_cache=True,
         threads=0, arrays_owned=False) -> BakeResult:
    """Bake every submesh (connected component) of a mesh.

    ``mask`` (booleans or numbers, one per vertex) limits the bake to submeshes with a nonzero
    vertex; ``angle_epsilon`` (radians) must lie in ANGLE_EPSILON_RANGE;
    ``previous_fingerprints`` (uint32 per vertex, from an earlier bake) skips submeshes whose
    geometry and options are unchanged; ``offsets`` (optional, float32 or uint8 (N, 4)) is
    written in place, keeping the values of submeshes not baked. Raises ValueError on malformed
    input (with the first offending element named) before anything is written. The core reads
    private copies of the mesh arrays, mask and fingerprints (another thread may write the
    caller's during the call); ``arrays_owned=True`` says the caller made them for this call and
    nothing else can reach them (the bake job's arrays read from Blender), so they are read as
    they are.
    """
    if origin not in ORIGIN_MODES:
        raise ValueError(f"origin must be one of {ORIGIN_MODES}, got {origin!r}")
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding must be one of {ENCODINGS}, got {encoding!r}")
    if mask is not None:
        mask = checked_mask(mask, "mask", row_count(positions))
    r = _core.bake(positions, edges, face_starts, face_sizes, corner_verts, mask=mask,
                   previous_fingerprints=previous_fingerprints, offsets=offsets,
                   angle_epsilon=float(angle_epsilon), origin=origin,
                   sort_axes_by_extent=bool(sort_axes_by_extent), axis_turn=checked_int(axis_turn, "axis_turn", 0, 23),
                   encoding=encoding, use_cache=bool(use_cache), threads=checked_int(threads, "threads", -2**31),
                   arrays_owned=bool(arrays_owned))
    return BakeResult(**r)


def find_submeshes(positions, edges, face_starts, face_sizes, corner_verts):
    """(submesh_of_vertex int32 (N,), count): components through edges and faces, numbered in
    order of each submesh's lowest vertex."""
    return _core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)


def face_offsets_from_corner_edges(corner_verts, corner_edges, edges, vertex_count, face_count, arrays_owned=False):
    """(face_starts, face_sizes) recovered from corner data, or None when they do not give exactly
    ``face_count`` faces of 3 or more corners (then read the face arrays themselves).
    ``arrays_owned``: as :func:`bake`'s."""
    starts, count = _core.face_starts_from_corner_edges(corner_verts, corner_edges, edges,
                                                        checked_int(vertex_count, "vertex_count"), bool(arrays_owned))
    if count != face_count:
        return None
    sizes = np.diff(starts, append=np.int32(len(corner_verts))).astype(np.int32)
    if len(sizes) and sizes.min() < 3:
        return None
    return starts, sizes


def validate_mesh(positions, edges, face_starts, face_sizes, corner_verts) -> None:
    """Raise ValueError naming the first malformed element (index out of range, NaN, ...)."""
    _core.validate_mesh(positions, edges, face_starts, face_sizes, corner_verts)


def corner_quaternion_uv(corner_uv, half, corner_verts, result: BakeResult, write_all=False):
    """Fill ``corner_uv`` (float32 (C, 2)) in place with each corner's (q.x, q.y) (half=0) or
    (q.z, q.w) (half=1); corners of submeshes this bake did not write are left as they are
    unless ``write_all``."""
    _core.expand_corner_quaternions(corner_uv, checked_int(half, "half", 0, 1), corner_verts, result.submesh_of_vertex,
                                    result.quaternions, None if write_all else result.written)


def axis_turn_matrices() -> np.ndarray:
    """(24, 3, 3): the axis-aligned turns; column i is the new local axis i in the derived frame.
    Index 0 is the identity."""
    return _core.axis_turn_matrices()


def axis_turn_label(index: int) -> str:
    """Short human label of turn ``index``, e.g. 'x=+Y y=-Z z=-X' (new axes in old ones)."""
    m = axis_turn_matrices()[checked_int(index, "axis turn", 0, 23)]
    parts = []
    for col, name in enumerate("xyz"):
        row = int(np.flatnonzero(m[:, col])[0])
        parts.append(f"{name}={'+' if m[row, col] > 0 else '-'}{'XYZ'[row]}")
    return " ".join(parts)


def rotate_vector(v, q):
    """The shaders' bm_rotate_vector, vectorised in float64: v + 2 cross(q.xyz, cross(q.xyz, v) +
    q.w v). v (..., 3), q (..., 4) broadcast."""
    v = np.asarray(v, np.float64)
    q = np.asarray(q, np.float64)
    u = q[..., :3]
    return v + 2.0 * np.cross(u, np.cross(u, v) + q[..., 3:4] * v)


def decode_offsets(rgba) -> np.ndarray:
    """The blog post's GetFragToOrigin (the shaders' bm_offset_from_color) in float64:
    f = (rgb * 2 - 1) / a. Accepts float RGBA, or uint8 RGBA (divided by 255 first, as a GPU reads
    normalised bytes)."""
    rgba = np.asarray(rgba)
    c = rgba.astype(np.float64) / 255.0 if rgba.dtype == np.uint8 else rgba.astype(np.float64)
    return (c[..., :3] * 2.0 - 1.0) / c[..., 3:4]


# A vertex lies on its box when it is within this share of the box's size along a local axis of
# one of the two faces across that axis; a piece with more vertices than a box's 8 and more than
# NOT_BOX_SHARE of them off its box does not look like a box (the bake warns).
ON_BOX_TOLERANCE = 0.05
NOT_BOX_SHARE = 0.25


def not_boxes(positions, submesh_of_vertex, quaternions):
    """(not_box bool (S,), off_box float64 (S,)): per submesh of more than 8 vertices, the share of
    its vertices off its box (the bounds of its vertices in its baked frame, ``quaternions`` (S, 4)
    x, y, z, w; 0 for a submesh of 8 vertices or fewer, which is never reported) and whether more
    than NOT_BOX_SHARE of them are. A box has none off, its faces cut into a grid or not, as has a
    box with one-segment bevels; a modelled torus, sphere or chain link has most of its vertices
    inside its bounding box. Costs nothing on meshes of 8-vertex boxes."""
    q = np.array(quaternions, np.float64).reshape(-1, 4)
    sub = checked_indices(submesh_of_vertex, "submesh_of_vertex", len(q))
    positions = np.array(positions, np.float64)
    if positions.shape != (len(sub), 3):
        raise ValueError(f"positions must be ({len(sub)}, 3) beside submesh_of_vertex, got {positions.shape}")
    counts = np.bincount(sub, minlength=len(q))
    off = np.zeros(len(q))
    checked = np.flatnonzero((counts > 8)[sub])
    if len(checked):
        sub = sub[checked]
        local = rotate_vector(positions[checked], q[sub] * (-1.0, -1.0, -1.0, 1.0))
        order = np.argsort(sub, kind="stable")
        grouped = sub[order]
        starts = np.flatnonzero(np.r_[True, grouped[1:] != grouped[:-1]])
        lo, hi = np.zeros((len(q), 3)), np.zeros((len(q), 3))
        lo[grouped[starts]] = np.minimum.reduceat(local[order], starts)
        hi[grouped[starts]] = np.maximum.reduceat(local[order], starts)
        tolerance = ON_BOX_TOLERANCE * (hi - lo)[sub]
        on_box = ((local - lo[sub] <= tolerance) | (hi[sub] - local <= tolerance)).any(axis=1)
        off = np.bincount(sub, weights=~on_box, minlength=len(q)) / np.maximum(counts, 1)
    return off > NOT_BOX_SHARE, off


def vertex_values_from_corners(corner_values, corner_verts, vertex_count) -> np.ndarray:
    """Per-vertex copy of a per-corner array (the bake writes the same quaternion to every corner
    of a vertex): the value of each vertex's last corner; vertices without corners get zeros."""
    corner_values = np.asarray(corner_values)
    vertex_count = checked_int(vertex_count, "vertex_count")
    out = np.zeros((vertex_count,) + corner_values.shape[1:], corner_values.dtype)
    out[checked_indices(corner_verts, "corner_verts", vertex_count)] = corner_values
    return out


def boxes_from_bake(positions, offsets, vertex_quaternions, submesh_of_vertex):
    """The box of every submesh as a shader sees it, from baked vertex data.

    ``positions`` (N, 3) object space, ``offsets`` (N, 4) the BoxOffset colour (float, or uint8
    raw bytes), ``vertex_quaternions`` (N, 4) (x, y, z, w), ``submesh_of_vertex`` (N,) ids 0..S-1.
    Returns float32 ``(origins (S, 3), quaternions (S, 4), half_extents (S, 3))``: origin = mean of
    the origins decoded at the submesh's vertices, half-extents = the largest |f| per local axis
    (the bounding box in the baked frame for BOUNDS origins)."""
    positions = np.asarray(positions, np.float64).reshape(-1, 3)
    ids = checked_indices(submesh_of_vertex, "submesh_of_vertex", row_count(positions))
    q = np.asarray(vertex_quaternions, np.float64).reshape(-1, 4)
    f = decode_offsets(offsets)
    count = int(ids.max()) + 1 if len(ids) else 0
    decoded = positions + rotate_vector(f, q)
    origins = np.zeros((count, 3))
    np.add.at(origins, ids, decoded)
    origins /= np.maximum(np.bincount(ids, minlength=count), 1)[:, None]
    half = np.zeros((count, 3))
    np.maximum.at(half, ids, np.abs(f))
    quats = np.zeros((count, 4))
    quats[ids] = q
    return origins.astype(np.float32), quats.astype(np.float32), half.astype(np.float32)


def render_baked_mesh(positions, offsets, corner_verts, corner_quaternions, submesh_of_vertex, object_to_clip,
                      object_to_view, width, height, **options) -> RenderResult:
    """:func:`render_boxes` of a baked mesh straight from its layers: ``positions`` (N, 3),
    ``offsets`` the BoxOffset colour per vertex (N, 4) or per corner (C, 4), ``corner_verts``
    (C,), ``corner_quaternions`` (C, 4) = BoxQuatXY and BoxQuatZW side by side,
    ``submesh_of_vertex`` (N,) (from :func:`find_submeshes` or :func:`bake`). Every submesh is
    drawn as its box (exact for box-shaped submeshes, the case the preview test checks)."""
    positions = np.asarray(positions).reshape(-1, 3)
    n = len(positions)
    offsets = np.asarray(offsets)
    if len(offsets) != n:
        offsets = vertex_values_from_corners(offsets, corner_verts, n)
    q = vertex_values_from_corners(np.asarray(corner_quaternions, np.float32), corner_verts, n)
    boxes = boxes_from_bake(positions, offsets, q, submesh_of_vertex)
    return render_boxes(*boxes, object_to_clip, object_to_view, width, height, **options)

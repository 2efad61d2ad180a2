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
in core_tools.py, the per-box parameters and hierarchy in core_boxes.py; both are part of this
API (imported here).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .core_tools import (  # noqa: F401 (re-exported: the submesh tools are part of this API)
    find_close_pairs, find_duplicate_submeshes, merge_passes, merge_targets, pack_uv_by_height, remove_vertices,
    select_linked_across, select_linked_submeshes, weld)
from .core_boxes import (  # noqa: F401 (re-exported: per-box parameters and hierarchy are part of this API)
    HIERARCHY_RULES, PARAM_NAMES, box_fingerprints, box_hierarchy, box_random, dominant_per_submesh, nearest_rows,
    not_boxes, parents_by_bone, preset_of_shape, reduce_per_submesh, render_boxes_by_shape)
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


# ---------------------------------------------------------------------------------------------
# Reference raymarcher (cpp/src/raymarch.cpp; mirrors shaders/glsl, see docs/PREVIEW.md)

SDF_PRESETS = ("BOX", "SPHERE", "ROUNDED_BOX", "CAPSULE", "CYLINDER", "TORUS", "LINK")
NORMAL_RULES = ("FORWARD", "TETRAHEDRAL", "CENTRAL")  # render_boxes' normal (cpp NormalRule, in order)


@dataclass
class MarchResult:
    """Per ray: ``hit`` (bool), ``positions`` (float32 (N, 3) box-local: the hit, or where the
    march stopped), ``normals`` (float32 (N, 3) unit SDF gradient at hits, zero on misses),
    ``steps`` (int32: SDF evaluations of the march)."""

    hit: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    steps: np.ndarray


@dataclass
class RenderResult:
    """Images with row 0 at the TOP: ``rgba`` (H, W, 4) float32, ``depth`` (H, W) window depth (0
    near plane, 1 far plane and background), ``normals`` (H, W, 3) object-space unit normals
    (zero where nothing was hit), ``steps`` (H, W) march steps summed over boxes; ``cost`` what a
    GPU spends on the frame (cpp RenderCost: fragments, marched_fragments, occluded_fragments,
    lod_fragments, sdf_evaluations, hidden_fragments, hidden_evaluations, covered_pixels)."""

    rgba: np.ndarray
    depth: np.ndarray
    normals: np.ndarray
    steps: np.ndarray
    cost: dict

    @property
    def coverage(self) -> np.ndarray:
        return self.depth < 1.0


def _preset_index(sdf) -> int:
    if sdf not in SDF_PRESETS:
        raise ValueError(f"sdf must be one of {SDF_PRESETS}, got {sdf!r}")
    return SDF_PRESETS.index(sdf)


def _normal_index(normal) -> int:
    if normal not in NORMAL_RULES:
        raise ValueError(f"normal must be one of {NORMAL_RULES}, got {normal!r}")
    return NORMAL_RULES.index(normal)


def _rows3(a, n, name):
    a = np.array(a, np.float32)  # a copy: checked here, then read by the core
    if a.shape == (3,):
        a = np.broadcast_to(a, (n, 3))
    if a.shape != (n, 3):
        raise ValueError(f"{name} must have shape (3,) or ({n}, 3), got {a.shape}")
    return np.ascontiguousarray(a)


def _check_finite(**arrays):
    for name, array in arrays.items():
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name} holds NaN or infinite values (first at row {int(np.argwhere(~np.isfinite(array))[0][0])})")


def raymarch(origins, directions, half_extents, *, sdf="BOX", max_steps=64, epsilon=1e-3, relaxation=1.0,
             max_distance=1e6, threads=0) -> MarchResult:
    """Sphere-trace rays in box-local coordinates, exactly as the viewport shader does.

    ``origins``, ``directions`` (N, 3) box-local (directions are normalised here);
    ``half_extents`` (3,) or (N, 3): the box each ray marches in, which also sizes the preset
    ``sdf`` (one of SDF_PRESETS). A ray starts where it enters its box (at its origin when that
    is inside) and stops at a hit (distance < ``epsilon``), after ``max_steps`` evaluations, when
    it leaves the box, or after travelling ``max_distance``. Each step advances ``relaxation`` x
    the distance. Raises ValueError on bad shapes or options."""
    origins = np.array(origins, np.float32, order="C")  # copies: checked here, then read by the core
    if origins.ndim != 2 or origins.shape[1] != 3:
        raise ValueError(f"origins must have shape (N, 3), got {origins.shape}")
    n = len(origins)
    directions, half_extents = _rows3(directions, n, "directions"), _rows3(half_extents, n, "half_extents")
    _check_finite(origins=origins, directions=directions, half_extents=half_extents)
    r = _core.raymarch(origins, directions, half_extents,
                       sdf=_preset_index(sdf), max_steps=checked_int(max_steps, "max_steps", -2**31), epsilon=float(epsilon),
                       relaxation=float(relaxation), max_distance=float(max_distance), threads=checked_int(threads, "threads", -2**31))
    return MarchResult(hit=r["hit"].astype(bool), positions=r["positions"], normals=r["normals"], steps=r["steps"])


def sdf_distance(sdf, points, half_extents) -> np.ndarray:
    """Distance (float32 (N,)) from box-local ``points`` (N, 3) to preset ``sdf`` of boxes with
    ``half_extents`` ((3,) or (N, 3))."""
    points = np.ascontiguousarray(points, np.float32).reshape(-1, 3)
    return _core.sdf_distance(_preset_index(sdf), points, _rows3(half_extents, len(points), "half_extents"))


def occluder_boxes(sdf, half_extents):
    """The shaders' conservative occluders (box_params.glsl bm_occluder_*: boxes inscribed in preset
    ``sdf``, clipped to the box, drawn by the hidden-box pre-pass) of boxes with ``half_extents``
    ((3,) or (N, 3)): ``(centres, halves)``, float32 (N, 4, 3) box-local; a zero half-extent: no
    box at that index."""
    half_extents = np.array(half_extents, np.float32, order="C").reshape(-1, 3)  # a copy: checked, then read
    _check_finite(half_extents=half_extents)
    return _core.occluder_boxes(_preset_index(sdf), half_extents)


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


def render_boxes(origins, quaternions, half_extents, object_to_clip, object_to_view, width, height, *,
                 base_color=(0.8, 0.8, 0.8), sdf="BOX", max_steps=64, epsilon=1e-3, relaxation=1.0,
                 max_distance=1e6, background=(0.0, 0.0, 0.0, 0.0), depth=None, rgba=None,
                 threads=0, order=None, early_depth=False, quality=1.0, normal="FORWARD",
                 occluders=False) -> RenderResult:
    """Render boxes as the viewport preview does (docs/PREVIEW.md), on the CPU.

    Boxes: ``origins`` (S, 3), ``quaternions`` (S, 4), ``half_extents`` (S, 3) in object space
    (see :func:`boxes_from_bake`). ``object_to_clip`` = projection @ view @ object matrix and
    ``object_to_view`` = view @ object matrix (4x4, row-major NumPy as in mathutils). One sample
    at each pixel centre. ``depth``/``rgba`` (optional (H, W) / (H, W, 4) float32) are images to
    composite into (depth-tested, updated in place); otherwise depth starts at 1.0 and rgba at
    ``background``. ``order``: the boxes' draw order (e.g. :func:`front_to_back`), each index once;
    ``early_depth``: fragments whose rasterised depth fails the depth test do not march (what a
    declared depth_greater keeps on a GPU); ``quality`` in (0, 1]: the preview's quality knob
    (docs/PREVIEW.md), 1 = every fragment marched in full; ``normal``, one of NORMAL_RULES: the
    shaders' forward differences (3 map() calls a hit), TETRAHEDRAL taps (4) or CENTRAL
    differences (6, the accuracy reference; cpp NormalRule). ``occluders``: the hidden-box
    pre-pass of the shaders (docs/PREVIEW.md, "Hidden boxes"): every fragment still runs, but one
    whose box entry lies behind the nearest conservative occluder (boxes inscribed in the preset,
    box_params.glsl) returns before its march, and no march goes past that depth."""
    width, height = checked_int(width, "width", 1), checked_int(height, "height", 1)
    # Copies: checked here, then read by the core (another thread may write the caller's arrays).
    origins = np.array(origins, np.float32, order="C").reshape(-1, 3)
    n = len(origins)
    quaternions = np.array(quaternions, np.float32, order="C").reshape(-1, 4)
    if depth is None:
        depth = np.ones((height, width), np.float32)
    if rgba is None:
        rgba = np.empty((height, width, 4), np.float32)
        rgba[:] = np.asarray(background, np.float32)
    for name, image, shape in (("depth", depth, (height, width)), ("rgba", rgba, (height, width, 4))):
        if image.shape != shape or image.dtype != np.float32 or not image.flags.c_contiguous:
            raise ValueError(f"{name} must be a C-contiguous float32 array of shape {shape}")
    half_extents = _rows3(half_extents, n, "half_extents")
    _check_finite(origins=origins, quaternions=quaternions, half_extents=half_extents)
    normals = np.zeros((height, width, 3), np.float32)
    steps = np.zeros((height, width), np.int32)
    if order is not None:
        order = checked_indices(order, "order", n)
        if order.shape != (n,):
            raise ValueError(f"order must be {n} box indices 0..{n - 1}")
        order = order.astype(np.uint32)
    cost = _core.render_boxes(origins, quaternions, half_extents,
                       np.ascontiguousarray(object_to_clip, np.float32), np.ascontiguousarray(object_to_view, np.float32),
                       np.ascontiguousarray(base_color, np.float32), rgba.reshape(-1, 4), depth,
                       normals.reshape(-1, 3), steps.reshape(-1), sdf=_preset_index(sdf),
                       max_steps=checked_int(max_steps, "max_steps", -2**31),
                       epsilon=float(epsilon), relaxation=float(relaxation), max_distance=float(max_distance),
                       threads=checked_int(threads, "threads", -2**31), order=order,
                       early_depth=bool(early_depth), quality=float(quality), normal=_normal_index(normal),
                       occluders=bool(occluders))
    return RenderResult(rgba=rgba, depth=depth, normals=normals, steps=steps, cost=cost)


def front_to_back(origins, eye) -> np.ndarray:
    """Draw order (uint32) of boxes centred at ``origins`` (S, 3), nearest first, for ``eye`` =
    (x, y, z, 1) a camera position or (x, y, z, 0) a view direction (orthographic), both in the
    boxes' space: the order early depth testing saves the most with."""
    origins = np.asarray(origins, np.float64).reshape(-1, 3)
    eye = np.asarray(eye, np.float64).reshape(4)
    key = (np.einsum("ij,ij->i", origins - eye[:3], origins - eye[:3]) if eye[3] > 0.5 else origins @ eye[:3])
    return np.argsort(key, kind="stable").astype(np.uint32)


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

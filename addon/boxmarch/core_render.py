"""The CPU reference raymarcher and renderer: the NumPy side of cpp/src/raymarch.cpp, which mirrors
the shaders (shaders/glsl, docs/PREVIEW.md) and against which the tests check the preview and the
engines. Part of the core API: core.py re-exports it."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .native import _core, checked_indices, checked_int

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


def preset_of_shape(shapes) -> np.ndarray:
    """int (S,): the SDF preset (index into SDF_PRESETS) each shape id picks, as the shaders'
    bm_sdf_by_id does: the id rounded to the nearest whole number, any id outside the presets
    the box (0)."""
    ids = np.floor(np.asarray(shapes, np.float64) + 0.5)
    return np.where((ids >= 0) & (ids < len(SDF_PRESETS)), ids, 0).astype(np.int64)


def render_boxes_by_shape(origins, quaternions, half_extents, shapes, object_to_clip, object_to_view, width, height,
                          **options):
    """render_boxes where each box draws the preset its shape id picks (``shapes`` (S,), as
    bm_sdf_by_id): the boxes of each preset are rendered in turn into the same images, the
    nearest hit winning by depth as in one pass (boxes never read each other). ``options`` as
    render_boxes, but ``sdf``."""
    if "sdf" in options:
        raise ValueError("render_boxes_by_shape takes the preset of each box from its shape id, not sdf")
    origins = np.asarray(origins, np.float32).reshape(-1, 3)
    presets = preset_of_shape(shapes)
    if presets.shape != (len(origins),):
        raise ValueError(f"shapes must hold one id per box ({len(origins)}), got shape {np.shape(shapes)}")
    quaternions = np.asarray(quaternions, np.float32).reshape(-1, 4)
    half_extents = np.broadcast_to(np.asarray(half_extents, np.float32), (len(origins), 3))
    result = None
    for preset in np.unique(presets) if len(presets) else [0]:
        chosen = presets == preset
        if result is not None:
            options.update(depth=result.depth, rgba=result.rgba)
        part = render_boxes(origins[chosen], quaternions[chosen], half_extents[chosen], object_to_clip,
                            object_to_view, width, height, sdf=SDF_PRESETS[preset], **options)
        if result is None:
            result = part
            continue
        won = np.any(part.normals != 0, axis=2)
        result.normals[won] = part.normals[won]
        result.steps += part.steps
    return result

"""Blender-free NumPy API of boxmarch.

Everything here takes and returns NumPy arrays; nothing imports ``bpy``. The heavy work runs in
the native module ``boxmarch._core`` with the GIL released.

Mesh arrays (the layout Blender uses):

* ``positions``: float32 (N, 3)
* ``edges``: int32 (E, 2) vertex pairs
* ``face_starts``, ``face_sizes``: int32 (F,): face f owns corners
  ``face_starts[f] .. face_starts[f] + face_sizes[f] - 1``
* ``corner_verts``: int32 (C,) the vertex of each corner

The baked data and its decode are documented in docs/FORMAT.md.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import _core

ORIGIN_MODES = ("BOUNDS", "MEAN")
ENCODINGS = ("FLOAT_COLOR", "BYTE_COLOR")
FRAME_SOURCES = ("FACES", "FACE_EDGE", "EDGES", "ONE_AXIS", "IDENTITY")
STATUS_BAKED, STATUS_UNCHANGED, STATUS_NOT_SELECTED = 0, 1, 2


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
         previous_fingerprints=None, offsets=None, angle_epsilon=0.1, origin="BOUNDS",
         sort_axes_by_extent=False, axis_turn=0, encoding="FLOAT_COLOR", use_cache=True,
         threads=0) -> BakeResult:
    """Bake every submesh (connected component) of a mesh.

    ``mask`` (uint8 per vertex) limits the bake to submeshes with a nonzero vertex;
    ``previous_fingerprints`` (uint32 per vertex, from an earlier bake) skips submeshes whose
    geometry and options are unchanged; ``offsets`` (optional, float32 or uint8 (N, 4)) is
    written in place, keeping the values of submeshes not baked. Raises ValueError on malformed
    input (with the first offending element named) before anything is written.
    """
    if origin not in ORIGIN_MODES:
        raise ValueError(f"origin must be one of {ORIGIN_MODES}, got {origin!r}")
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding must be one of {ENCODINGS}, got {encoding!r}")
    r = _core.bake(positions, edges, face_starts, face_sizes, corner_verts, mask=mask,
                   previous_fingerprints=previous_fingerprints, offsets=offsets,
                   angle_epsilon=float(angle_epsilon), origin=origin,
                   sort_axes_by_extent=bool(sort_axes_by_extent), axis_turn=int(axis_turn),
                   encoding=encoding, use_cache=bool(use_cache), threads=int(threads))
    return BakeResult(**r)


def find_submeshes(positions, edges, face_starts, face_sizes, corner_verts):
    """(submesh_of_vertex int32 (N,), count): components through edges and faces, numbered in
    order of each submesh's lowest vertex."""
    return _core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)


def face_offsets_from_corner_edges(corner_verts, corner_edges, edges, vertex_count, face_count):
    """(face_starts, face_sizes) recovered from corner data, or None when they do not give exactly
    ``face_count`` faces of 3 or more corners (then read the face arrays themselves)."""
    starts, count = _core.face_starts_from_corner_edges(corner_verts, corner_edges, edges, int(vertex_count))
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
    _core.expand_corner_quaternions(corner_uv, half, corner_verts, result.submesh_of_vertex,
                                    result.quaternions, None if write_all else result.written)


def axis_turn_matrices() -> np.ndarray:
    """(24, 3, 3): the axis-aligned turns; column i is the new local axis i in the derived frame.
    Index 0 is the identity."""
    return _core.axis_turn_matrices()


def axis_turn_label(index: int) -> str:
    """Short human label of turn ``index``, e.g. 'x=+Y y=-Z z=-X' (new axes in old ones)."""
    m = axis_turn_matrices()[index]
    parts = []
    for col, name in enumerate("xyz"):
        row = int(np.flatnonzero(m[:, col])[0])
        parts.append(f"{name}={'+' if m[row, col] > 0 else '-'}{'XYZ'[row]}")
    return " ".join(parts)


def rotate_vector(v, q):
    """The shader's rotate_vector, vectorised in float64: v + 2 cross(q.xyz, cross(q.xyz, v) +
    q.w v). v (..., 3), q (..., 4) broadcast."""
    v = np.asarray(v, np.float64)
    q = np.asarray(q, np.float64)
    u = q[..., :3]
    return v + 2.0 * np.cross(u, np.cross(u, v) + q[..., 3:4] * v)


def decode_offsets(rgba) -> np.ndarray:
    """The seed's GetFragToOrigin in float64: f = (rgb * 2 - 1) / a. Accepts float RGBA, or uint8
    RGBA (divided by 255 first, as a GPU reads normalised bytes)."""
    rgba = np.asarray(rgba)
    c = rgba.astype(np.float64) / 255.0 if rgba.dtype == np.uint8 else rgba.astype(np.float64)
    return (c[..., :3] * 2.0 - 1.0) / c[..., 3:4]

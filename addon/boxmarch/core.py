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
    Entries of submeshes that were not baked are zero.
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


# ---------------------------------------------------------------------------------------------
# Submesh tools (docs/TOOLS.md). Submesh ids come from find_submeshes; masks are any array of
# booleans or 0/1 values, one per vertex (or per submesh / face where named so).

def _mask(values, name, length) -> np.ndarray:
    mask = np.ascontiguousarray(np.asarray(values) != 0, dtype=np.uint8)
    if mask.shape != (length,):
        raise ValueError(f"{name} must have shape ({length},), got {np.shape(values)}")
    return mask


def find_close_pairs(positions, radius, groups=None, method="HASH", threads=0) -> np.ndarray:
    """uint32 (P, 2): every pair i < j of points with Euclidean distance <= ``radius``, sorted.
    ``groups`` (int32 per point, optional): only pairs from different groups; negative groups
    leave the point out. ``method``: 'HASH' (hash grid, threaded) or 'KDTREE' (nanoflann radius
    searches, the reference)."""
    return _core.find_close_pairs(positions, float(radius), groups=groups, method=method, threads=int(threads))


def select_linked_submeshes(selected, submesh_of_vertex, submesh_count):
    """(uint8 mask per vertex, submeshes selected): every submesh with a selected vertex, whole."""
    ids = np.asarray(submesh_of_vertex)
    return _core.select_linked_submeshes(_mask(selected, "selected", len(ids)), ids, int(submesh_count))


def select_linked_across(positions, selected, submesh_of_vertex, submesh_count, epsilon=1e-4, threads=0):
    """(uint8 mask per vertex, submeshes selected): flood fill from the selection through edges
    and through vertices of other submeshes within ``epsilon`` (true distance, inclusive)."""
    ids = np.asarray(submesh_of_vertex)
    return _core.select_linked_across(positions, _mask(selected, "selected", len(ids)), ids,
                                      int(submesh_count), float(epsilon), int(threads))


def find_duplicate_submeshes(positions, submesh_of_vertex, submesh_count, candidates=None,
                             tolerance=1e-4, threads=0):
    """(duplicate_of int32 per submesh, count). A candidate submesh (``candidates``: mask per
    submesh, None: all) duplicates an earlier kept candidate when both have the same vertex
    count and its vertices pair one-to-one with that one's within ``tolerance``; duplicate_of
    names the kept submesh, -1 where the submesh is kept or not a candidate."""
    if candidates is not None:
        candidates = _mask(candidates, "candidates", int(submesh_count))
    return _core.find_duplicate_submeshes(positions, submesh_of_vertex, int(submesh_count), candidates,
                                          float(tolerance), int(threads))


def merge_passes(positions, submesh_of_vertex, submesh_count, chosen=None, distance=1e-3, threads=0):
    """(pass_of_vertex int32, passes): a plan for merging by distance inside each chosen
    submesh (mask per submesh, None: all) with a selection-based merge: pass k selects the
    vertices marked k and merges them; -1 marks vertices with no partner in their submesh."""
    count = int(submesh_count)
    chosen = np.ones(count, np.uint8) if chosen is None else _mask(chosen, "chosen", count)
    return _core.merge_passes(positions, submesh_of_vertex, count, chosen, float(distance), int(threads))


def pack_uv_by_height(corner_uv, positions, edges, face_starts, face_sizes, corner_verts, *,
                      vertex_height, submesh_of_vertex, submesh_count, face_mask=None,
                      padding=0.002, max_per_row=0, lock_overlapping=False) -> dict:
    """Pack the UV islands of the masked faces (None: all) into the unit square in rows, sorted
    by the height of their submesh (``vertex_height`` per vertex, e.g. world Z; highest on top),
    at one uniform scale with ``padding`` around every island; ``max_per_row`` 0 means no limit.
    ``corner_uv`` (float32 (C, 2)) is written in place for the masked faces only. Returns
    {'islands', 'groups', 'rows', 'scale'}. Raises ValueError (nothing written) on bad input."""
    if face_mask is not None:
        face_mask = _mask(face_mask, "face_mask", len(face_starts))
    if int(max_per_row) < 0:
        raise ValueError(f"max_per_row must be >= 0, got {max_per_row}")
    return _core.pack_uv_by_height(corner_uv, positions, edges, face_starts, face_sizes, corner_verts,
                                   face_mask=face_mask,
                                   vertex_height=np.ascontiguousarray(vertex_height, np.float32),
                                   submesh_of_vertex=submesh_of_vertex, submesh_count=int(submesh_count),
                                   padding=float(padding), max_per_row=int(max_per_row),
                                   lock_overlapping=bool(lock_overlapping))


def merge_targets(positions, submesh_of_vertex, submesh_count, chosen=None, distance=1e-3, threads=0):
    """Blender's Merge by Distance inside each chosen submesh (mask per submesh, None: all):
    (target int32 per vertex, merged positions float32 (N, 3), vertices merged away). A vertex
    merges into target[v] (itself for survivors); targets sit at their cluster's centroid."""
    count = int(submesh_count)
    chosen = np.ones(count, np.uint8) if chosen is None else _mask(chosen, "chosen", count)
    return _core.merge_targets(positions, submesh_of_vertex, count, chosen, float(distance), int(threads))


def weld(positions, edges, face_starts, face_sizes, corner_verts, target, corner_edges=None) -> dict:
    """The mesh after merging every vertex v into target[v], as Blender's weld leaves it: faces
    lose corners that merge into the next one and go below 3 corners; edges are the distinct
    images of the old ones; survivors keep their order. Returns new 'edges', 'face_starts',
    'corner_verts', 'corner_edges' and, per new element, the old element it comes from
    ('vertex_source', 'edge_source', 'face_source', 'corner_source'); 'needs_blender' is True
    when Blender's weld would also split or dedupe faces (then merge with Blender itself).
    ``corner_edges`` (int32 per corner, the edge to the next corner, as Blender stores it) makes
    the new corner edges a lookup instead of a search."""
    return _core.weld_topology(positions, edges, face_starts, face_sizes, corner_verts,
                               np.ascontiguousarray(target, np.int32), corner_edges)


def remove_vertices(positions, edges, face_starts, face_sizes, corner_verts, remove, corner_edges) -> dict:
    """The mesh without the vertices marked in ``remove`` and every edge and face touching them,
    survivors in their order: the same dict as :func:`weld` (with 'needs_blender' False)."""
    keep = ~_mask(remove, "remove", len(positions)).astype(bool)
    new_index = np.cumsum(keep, dtype=np.int64) - 1
    edges = np.asarray(edges).reshape(-1, 2)
    keep_edge = keep[edges[:, 0]] & keep[edges[:, 1]]
    new_edge = np.cumsum(keep_edge, dtype=np.int64) - 1
    corner_verts = np.asarray(corner_verts)
    corner_keep_face = np.logical_and.reduceat(keep[corner_verts], face_starts) if len(face_starts) else np.zeros(0, bool)
    keep_corner = np.repeat(corner_keep_face, face_sizes)
    sizes = np.asarray(face_sizes)[corner_keep_face]
    return {
        "vertex_source": np.flatnonzero(keep).astype(np.int32),
        "edge_source": np.flatnonzero(keep_edge).astype(np.int32),
        "edges": new_index[edges[keep_edge]].astype(np.int32),
        "face_source": np.flatnonzero(corner_keep_face).astype(np.int32),
        "face_starts": (np.cumsum(sizes) - sizes).astype(np.int32),
        "corner_source": np.flatnonzero(keep_corner).astype(np.int32),
        "corner_verts": new_index[corner_verts[keep_corner]].astype(np.int32),
        "corner_edges": new_edge[np.asarray(corner_edges)[keep_corner]].astype(np.int32),
        "needs_blender": False,
    }

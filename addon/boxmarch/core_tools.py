"""The submesh tools' NumPy API (docs/TOOLS.md), part of boxmarch.core (which re-exports every
function here). Submesh ids come from find_submeshes; masks are any array of booleans or 0/1
values, one per vertex (or per submesh / face where named so)."""
from __future__ import annotations

import numpy as np

from .native import _core, checked_indices, checked_int, checked_mask, row_count

# The cleanup tools' defaults, stated once: the functions below, their jobs (tool_jobs, whose
# operators take them) and the command line's options read them here.
DUPLICATE_TOLERANCE = 1e-4
MERGE_DISTANCE = 1e-3
PACK_UV_PADDING = 0.002


def find_close_pairs(positions, radius, groups=None, method="HASH", threads=0) -> np.ndarray:
    """uint32 (P, 2): every pair i < j of points with Euclidean distance <= ``radius``, sorted.
    ``groups`` (int32 per point, optional): only pairs from different groups; negative groups
    leave the point out. ``method``: 'HASH' (hash grid, threaded) or 'KDTREE' (nanoflann radius
    searches, the reference)."""
    return _core.find_close_pairs(positions, float(radius), groups=groups, method=method, threads=checked_int(threads, "threads", -2**31))


def select_linked_submeshes(selected, submesh_of_vertex, submesh_count):
    """(uint8 mask per vertex, submeshes selected): every submesh with a selected vertex, whole."""
    ids = np.asarray(submesh_of_vertex)
    return _core.select_linked_submeshes(checked_mask(selected, "selected", len(ids)), ids, checked_int(submesh_count, "submesh_count"))


def select_linked_across(positions, selected, submesh_of_vertex, submesh_count, epsilon=1e-4, threads=0):
    """(uint8 mask per vertex, submeshes selected): flood fill from the selection through edges
    and through vertices of other submeshes within ``epsilon`` (true distance, inclusive)."""
    ids = np.asarray(submesh_of_vertex)
    return _core.select_linked_across(positions, checked_mask(selected, "selected", len(ids)), ids,
                                      checked_int(submesh_count, "submesh_count"), float(epsilon), checked_int(threads, "threads", -2**31))


def find_duplicate_submeshes(positions, submesh_of_vertex, submesh_count, candidates=None,
                             tolerance=DUPLICATE_TOLERANCE, threads=0):
    """(duplicate_of int32 per submesh, count). A candidate submesh (``candidates``: mask per
    submesh, None: all) duplicates an earlier kept candidate when both have the same vertex
    count and its vertices pair one-to-one with that one's within ``tolerance``; duplicate_of
    names the kept submesh, -1 where the submesh is kept or not a candidate."""
    if candidates is not None:
        candidates = checked_mask(candidates, "candidates", checked_int(submesh_count, "submesh_count"))
    return _core.find_duplicate_submeshes(positions, submesh_of_vertex, checked_int(submesh_count, "submesh_count"), candidates,
                                          float(tolerance), checked_int(threads, "threads", -2**31))


def merge_passes(positions, submesh_of_vertex, submesh_count, chosen=None, distance=MERGE_DISTANCE, threads=0):
    """(pass_of_vertex int32, passes): a plan for merging by distance inside each chosen
    submesh (mask per submesh, None: all) with a selection-based merge: pass k selects the
    vertices marked k and merges them; -1 marks vertices with no partner in their submesh."""
    count = checked_int(submesh_count, "submesh_count")
    chosen = np.ones(count, np.uint8) if chosen is None else checked_mask(chosen, "chosen", count)
    return _core.merge_passes(positions, submesh_of_vertex, count, chosen, float(distance), checked_int(threads, "threads", -2**31))


def pack_uv_by_height(corner_uv, positions, edges, face_starts, face_sizes, corner_verts, *,
                      vertex_height, submesh_of_vertex, submesh_count, face_mask=None,
                      padding=PACK_UV_PADDING, max_per_row=0, lock_overlapping=False) -> dict:
    """Pack the UV islands of the masked faces (None: all) into the unit square in rows, sorted
    by the height of their submesh (``vertex_height`` per vertex, e.g. world Z; highest on top),
    at one uniform scale with ``padding`` around every island; ``max_per_row`` 0 means no limit.
    ``corner_uv`` (float32 (C, 2)) is written in place for the masked faces only. Returns
    {'islands', 'groups', 'rows', 'scale'}. Raises ValueError (nothing written) on bad input."""
    if face_mask is not None:
        face_mask = checked_mask(face_mask, "face_mask", len(face_starts))
    max_per_row = checked_int(max_per_row, "max_per_row")
    return _core.pack_uv_by_height(corner_uv, positions, edges, face_starts, face_sizes, corner_verts,
                                   face_mask=face_mask,
                                   vertex_height=np.ascontiguousarray(vertex_height, np.float32),
                                   submesh_of_vertex=submesh_of_vertex, submesh_count=checked_int(submesh_count, "submesh_count"),
                                   padding=float(padding), max_per_row=int(max_per_row),
                                   lock_overlapping=bool(lock_overlapping))


def merge_targets(positions, submesh_of_vertex, submesh_count, chosen=None, distance=MERGE_DISTANCE, threads=0):
    """Blender's Merge by Distance inside each chosen submesh (mask per submesh, None: all):
    (target int32 per vertex, merged positions float32 (N, 3), vertices merged away). A vertex
    merges into target[v] (itself for survivors); targets sit at their cluster's centroid."""
    count = checked_int(submesh_count, "submesh_count")
    chosen = np.ones(count, np.uint8) if chosen is None else checked_mask(chosen, "chosen", count)
    return _core.merge_targets(positions, submesh_of_vertex, count, chosen, float(distance), checked_int(threads, "threads", -2**31))


def weld(positions, edges, face_starts, face_sizes, corner_verts, target, corner_edges=None) -> dict:
    """The mesh after merging every vertex v into target[v], as Blender's weld leaves it: faces
    lose corners that merge into the next one and go below 3 corners; edges are the distinct
    images of the old ones; survivors keep their order. Returns new 'edges', 'face_starts',
    'corner_verts', 'corner_edges' and, per new element, the old element it comes from
    ('vertex_source', 'edge_source', 'face_source', 'corner_source'); 'incomplete' is True
    when Blender's weld would also split or dedupe faces (then merge with Blender itself).
    ``corner_edges`` (int32 per corner, the edge to the next corner, as Blender stores it) makes
    the new corner edges a lookup instead of a search."""
    return _core.weld_topology(positions, edges, face_starts, face_sizes, corner_verts,
                               checked_indices(target, "target", row_count(positions)), corner_edges)


def remove_vertices(positions, edges, face_starts, face_sizes, corner_verts, remove, corner_edges) -> dict:
    """The mesh without the vertices marked in ``remove`` and every edge and face touching them,
    survivors in their order: the same dict as :func:`weld` (with 'incomplete' False). Raises
    ValueError on a malformed mesh (as :func:`boxmarch.core.validate_mesh`), a corner edge out of
    range, or faces naming more corners than there are (overlapping faces, as weld)."""
    # Copies, validated and then used: another thread writing the caller's arrays cannot turn a
    # checked index into one out of range.
    positions, edges, face_starts, face_sizes, corner_verts = (
        np.array(a) for a in (positions, edges, face_starts, face_sizes, corner_verts))
    _core.validate_mesh(positions, edges, face_starts, face_sizes, corner_verts)
    keep = ~checked_mask(remove, "remove", len(positions)).astype(bool)
    edges = edges.reshape(-1, 2)
    corner_edges = checked_indices(corner_edges, "corner_edges", len(edges))
    if corner_edges.shape != corner_verts.shape:
        raise ValueError(f"corner_edges must have shape {corner_verts.shape}, got {corner_edges.shape}")
    starts, sizes = np.asarray(face_starts, np.int64), np.asarray(face_sizes, np.int64)
    if sizes.sum() > len(corner_verts):
        raise ValueError(f"faces name {int(sizes.sum())} corners but there are {len(corner_verts)}: faces overlap")
    # Each face's corners, face after face (faces may be stored in any order of their starts).
    first_of_run = np.cumsum(sizes) - sizes
    face_corner = np.repeat(starts - first_of_run, sizes) + np.arange(int(sizes.sum()))
    face_of_corner = np.repeat(np.arange(len(sizes)), sizes)
    dropped = np.zeros(len(sizes), bool)
    np.logical_or.at(dropped, face_of_corner, ~keep[corner_verts[face_corner]])
    keep_face = ~dropped
    kept_corners = face_corner[keep_face[face_of_corner]]
    new_index = np.cumsum(keep, dtype=np.int64) - 1
    keep_edge = keep[edges[:, 0]] & keep[edges[:, 1]]
    new_edge = np.cumsum(keep_edge, dtype=np.int64) - 1
    kept_sizes = sizes[keep_face]
    return {
        "vertex_source": np.flatnonzero(keep).astype(np.int32),
        "edge_source": np.flatnonzero(keep_edge).astype(np.int32),
        "edges": new_index[edges[keep_edge]].astype(np.int32),
        "face_source": np.flatnonzero(keep_face).astype(np.int32),
        "face_starts": (np.cumsum(kept_sizes) - kept_sizes).astype(np.int32),
        "corner_source": kept_corners.astype(np.int32),
        "corner_verts": new_index[corner_verts[kept_corners]].astype(np.int32),
        "corner_edges": new_edge[corner_edges[kept_corners]].astype(np.int32),
        "incomplete": False,
    }

"""Per-box parameters and the box hierarchy: the NumPy side of cpp/src/box_params.cpp and
cpp/src/hierarchy*.cpp (part of the core API: core.py re-exports them). docs/FORMAT.md states
what each value means and where each layout carries it."""
from __future__ import annotations

import numpy as np

from .native import _core, checked_indices, checked_int

# The four floats every box carries, in their order in every layout and table.
PARAM_NAMES = ("shape", "material", "random", "user")
HIERARCHY_RULES = ("ATTRIBUTE", "CONTAINMENT", "CHAIN", "BONES")
# BONES parents are found in Python (parents_by_bone) and checked as given ones.
_RULE_CODES = {"ATTRIBUTE": 0, "CONTAINMENT": 1, "CHAIN": 2, "BONES": 0}


def reduce_per_submesh(values, submesh_of_element, submesh_count):
    """One value tuple per submesh from per-element ``values`` ((E,) or (E, k), k <= 4) and
    ``submesh_of_element`` (E,): the tuple most of the submesh's elements hold (ties: the one of
    the lowest element). Returns (float32 (S, k), bool (S,) disagrees, disagreeing count)."""
    values = np.asarray(values, np.float32)
    flat = values.ndim == 1
    values = np.ascontiguousarray(values.reshape(len(values), -1))
    submesh_count = checked_int(submesh_count, "submesh_count")
    ids = checked_indices(submesh_of_element, "submesh_of_element", submesh_count)
    out, disagrees, count = _core.reduce_per_submesh(values, ids, submesh_count)
    return (out[:, 0] if flat else out), disagrees.astype(bool), int(count)


def box_fingerprints(fingerprints, submesh_of_vertex, submesh_count) -> np.ndarray:
    """uint32 (S,): the bake fingerprint of each submesh (that of its lowest vertex; every vertex
    of a submesh holds the same one)."""
    submesh_count = checked_int(submesh_count, "submesh_count")
    ids = checked_indices(submesh_of_vertex, "submesh_of_vertex", submesh_count)
    fp = np.array(fingerprints, np.uint32)
    if fp.shape != ids.shape:
        raise ValueError(f"fingerprints must have shape {ids.shape} (one per vertex), got {fp.shape}")
    first = np.full(submesh_count, len(ids), np.int64)
    first[ids[::-1]] = np.arange(len(ids))[::-1]  # the last write of each box is its lowest vertex
    return np.where(first < len(ids), fp[np.minimum(first, max(len(ids) - 1, 0))], 0).astype(np.uint32)


def box_random(box_fingerprints_, seed=0) -> np.ndarray:
    """float32 (S,) in [0, 1): each box's random value, stable while its fingerprint (geometry
    and bake options) and ``seed`` (0 .. 2^32-1) stay the same."""
    return _core.box_random(np.ascontiguousarray(box_fingerprints_, np.uint32),
                            checked_int(seed, "random seed", 0, 2**32 - 1))


def dominant_per_submesh(weights, submesh_of_vertex, submesh_count) -> np.ndarray:
    """int64 (S,): the column of ``weights`` (vertices, B) with the largest sum over each
    submesh's vertices (ties: the lower column); -1 where the submesh has no weight."""
    submesh_count = checked_int(submesh_count, "submesh_count")
    ids = checked_indices(submesh_of_vertex, "submesh_of_vertex", submesh_count)
    weights = np.array(weights, np.float64)
    if weights.ndim != 2 or len(weights) != len(ids):
        raise ValueError(f"weights must have shape ({len(ids)}, bones) (one row per vertex), got {weights.shape}")
    total = np.zeros((submesh_count, weights.shape[1]))
    np.add.at(total, ids, weights)
    if not weights.shape[1]:
        return np.full(submesh_count, -1, np.int64)
    return np.where(total.max(axis=1) > 0, total.argmax(axis=1), -1)


def nearest_rows(points, candidates) -> np.ndarray:
    """int64 (n,): the row of ``candidates`` (m, 3) nearest each of ``points`` (n, 3): the
    smallest sum of squared coordinate differences in float64 (ties: the lower row), found on a
    k-d tree of the candidates (cpp/src/nearest_points.cpp). Raises ValueError on a NaN or infinite
    coordinate, or on points without candidates."""
    # Copies: the checks below must hold for what the core then reads.
    points = np.array(points, np.float64, order="C")
    candidates = np.array(candidates, np.float64, order="C")
    if not (np.all(np.isfinite(points)) and np.all(np.isfinite(candidates))):
        raise ValueError("nearest_rows: points and candidates must have finite coordinates")
    if len(points) and not len(candidates):
        raise ValueError(f"nearest_rows: {len(points)} points but no candidate to be nearest to")
    return _core.nearest_points(points, candidates)


def parents_by_bone(box_bone, bone_parent, origins) -> np.ndarray:
    """int32 (S,): each box's parent under the BONES rule. ``box_bone`` (S,): each box's bone
    (-1: none), ``bone_parent`` (B,): each bone's parent bone (-1: a root bone). A box's parent
    is the box of its bone's parent bone whose origin lies nearest its own (nearest_rows; ties:
    the lower number); a parent bone that holds no box passes to its own parent; -1 where no
    ancestor bone holds a box. Raises ValueError on a bone out of range or a cycle of bones."""
    bones = len(bone_parent)
    bone_parent = checked_indices(bone_parent, "bone_parent", bones, lowest=-1)
    box_bone = checked_indices(box_bone, "box_bone", bones, lowest=-1)
    origins = np.array(origins, np.float64).reshape(-1, 3)
    if bone_parent.ndim != 1 or box_bone.ndim != 1 or len(origins) != len(box_bone):
        raise ValueError(f"parents_by_bone: box_bone {box_bone.shape} and origins {origins.shape} must have one row "
                         f"per box, bone_parent {bone_parent.shape} one per bone")
    boxes_of_bone = np.bincount(box_bone[box_bone >= 0], minlength=bones)
    # holder[b]: b's nearest ancestor bone holding a box (-1: none), one step up every ancestor
    # without a box per pass.
    holder = np.where(bone_parent >= 0, bone_parent, -1)
    for _ in range(bones + 1):
        passing = (holder >= 0) & (boxes_of_bone[np.maximum(holder, 0)] == 0)
        if not passing.any():
            break
        holder[passing] = bone_parent[holder[passing]]
    else:
        raise ValueError("parents_by_bone: the bones' parents form a cycle")
    # A stable sort keeps each bone's boxes ascending, so the lowest row is the lowest box.
    order = np.argsort(box_bone, kind="stable")
    start = np.searchsorted(box_bone[order], np.arange(bones + 1))
    parent = np.full(len(box_bone), -1, np.int32)
    for bone in np.flatnonzero((boxes_of_bone > 0) & (holder >= 0)):
        up = holder[bone]
        children, candidates = order[start[bone]:start[bone + 1]], order[start[up]:start[up + 1]]
        parent[children] = candidates[nearest_rows(origins[children], origins[candidates])]
    return parent


def box_hierarchy(origins, quaternions, half_extents, rule="ATTRIBUTE", given_parent=None):
    """(parent int32 (S,), depth int32 (S,), deepest): each box's parent box (-1: a root) and its
    depth (0 at a root). ``rule``: ATTRIBUTE takes ``given_parent`` (int (S,), -1 for roots;
    None: every box a root), CONTAINMENT the smallest larger box holding the box's origin, CHAIN
    the nearest lower-numbered box (instances along a curve are numbered along it), BONES takes
    ``given_parent`` (parents_by_bone) as ATTRIBUTE does. Raises ValueError on a parent out of range, a box its own parent or a cycle,
    and (any rule) on a NaN or infinite origin or quaternion or a negative or NaN half-extent."""
    if rule not in _RULE_CODES:
        raise ValueError(f"hierarchy rule must be one of {HIERARCHY_RULES}, got {rule!r}")
    origins = np.ascontiguousarray(origins, np.float64).reshape(-1, 3)
    n = len(origins)
    if rule == "BONES" and given_parent is None:
        raise ValueError("the BONES rule needs the parents found from the bones (parents_by_bone)")
    if rule == "ATTRIBUTE" and given_parent is None:
        given_parent = np.full(n, -1, np.int32)
    given = None
    if given_parent is not None:
        given = np.array(given_parent)  # a copy: checked here, read by the core
        if given.shape != (n,) or not np.all(np.isfinite(given)) or np.any(given != np.round(given)):
            raise ValueError(f"given parents must be {n} whole numbers (one per box)")
        outside = np.flatnonzero((given < -1) | (given >= n))
        if len(outside):  # named here as given: the int32 the core checks would show a clipped value
            box = int(outside[0])
            raise ValueError(f"box {box} names parent {int(given[box])}, outside -1..{n - 1}")
        given = np.ascontiguousarray(given, np.int32)
    parent, depth, deepest = _core.box_hierarchy(
        origins, np.ascontiguousarray(quaternions, np.float32).reshape(-1, 4),
        np.ascontiguousarray(half_extents, np.float64).reshape(-1, 3), _RULE_CODES[rule], given)
    return parent, depth, int(deepest)

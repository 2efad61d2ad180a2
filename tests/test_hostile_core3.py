"""Hostile inputs through boxmarch.core, round 3: the index rule for every function of the NumPy API
that takes ids or indices. An index is checked before any narrowing: an int64 of 2**32 + k is
refused, not wrapped to k; 1.7 is refused, not truncated to 1; one below the lowest valid value
(-1 where -1 means none) or at the limit is refused with a one-line ValueError, not wrapped by
NumPy or raised as a bare IndexError. docs/CHECKS.md lists the cases."""
import numpy as np
import pytest

from boxmarch import core, scenes

ARRAYS, *_ = scenes.random_boxes(6, seed=3, spread=3.0)
POSITIONS, EDGES, FACE_STARTS, FACE_SIZES, CORNER_VERTS = ARRAYS
RESULT = core.bake(*ARRAYS)
SV, S = RESULT.submesh_of_vertex, RESULT.submesh_count
N, E = len(POSITIONS), len(EDGES)
BOXES = (RESULT.origins, RESULT.quaternions, RESULT.half_extents)
CORNER_Q = np.tile(np.float32([0, 0, 0, 1]), (len(CORNER_VERTS), 1))
VIEW = np.eye(4, dtype=np.float32)
VIEW[2, 3] = -20.0


def _with_mesh(corner_verts):
    return POSITIONS, EDGES, FACE_STARTS, FACE_SIZES, corner_verts


# name -> (call taking the index array, a valid index array, lowest valid value, limit)
INDEX_ARGUMENTS = {
    "reduce_per_submesh ids": (lambda ids: core.reduce_per_submesh(np.ones(N, np.float32), ids, S), SV, 0, S),
    "box_fingerprints ids": (lambda ids: core.box_fingerprints(RESULT.fingerprints, ids, S), SV, 0, S),
    "not_boxes submesh_of_vertex": (lambda ids: core.not_boxes(POSITIONS, ids, RESULT.quaternions), SV, 0, S),
    "dominant_per_submesh ids": (lambda ids: core.dominant_per_submesh(np.ones((N, 2)), ids, S), SV, 0, S),
    "parents_by_bone box_bone": (lambda ids: core.parents_by_bone(ids, [-1, 0, 1], RESULT.origins),
                                 np.arange(S) % 3, -1, 3),
    "parents_by_bone bone_parent": (lambda ids: core.parents_by_bone(np.arange(S) % 3, ids, RESULT.origins),
                                    np.array([-1, 0, 1]), -1, 3),
    "box_hierarchy given_parent": (lambda ids: core.box_hierarchy(*BOXES, "ATTRIBUTE", ids), np.arange(-1, S - 1),
                                   -1, S),
    "box_hierarchy BONES parents": (lambda ids: core.box_hierarchy(*BOXES, "BONES", ids), np.arange(-1, S - 1), -1, S),
    "boxes_from_bake submesh_of_vertex": (lambda ids: core.boxes_from_bake(POSITIONS, RESULT.offsets,
                                                                           CORNER_Q[:N], ids), SV, 0, N),
    "render_baked_mesh submesh_of_vertex": (lambda ids: core.render_baked_mesh(
        POSITIONS, RESULT.offsets, CORNER_VERTS, CORNER_Q, ids, VIEW, VIEW, 4, 4), SV, 0, N),
    "vertex_values_from_corners corner_verts": (lambda ids: core.vertex_values_from_corners(CORNER_Q, ids, N),
                                                CORNER_VERTS, 0, N),
    "render_boxes order": (lambda ids: core.render_boxes(*BOXES, VIEW, VIEW, 4, 4, order=ids), np.arange(S), 0, S),
    "select_linked_submeshes ids": (lambda ids: core.select_linked_submeshes(np.ones(N), ids, S), SV, 0, S),
    "select_linked_across ids": (lambda ids: core.select_linked_across(POSITIONS, np.ones(N), ids, S), SV, 0, S),
    "find_duplicate_submeshes ids": (lambda ids: core.find_duplicate_submeshes(POSITIONS, ids, S), SV, 0, S),
    "merge_passes ids": (lambda ids: core.merge_passes(POSITIONS, ids, S), SV, 0, S),
    "merge_targets ids": (lambda ids: core.merge_targets(POSITIONS, ids, S), SV, 0, S),
    "pack_uv_by_height submesh_of_vertex": (lambda ids: core.pack_uv_by_height(
        np.zeros((len(CORNER_VERTS), 2), np.float32), *ARRAYS, vertex_height=POSITIONS[:, 2],
        submesh_of_vertex=ids, submesh_count=S), SV, 0, S),
    "weld target": (lambda ids: core.weld(*ARRAYS, ids), np.arange(N), 0, N),
    "remove_vertices corner_edges": (lambda ids: core.remove_vertices(*ARRAYS, np.zeros(N), ids),
                                     np.arange(len(CORNER_VERTS)) % E, 0, E),
    "face_offsets_from_corner_edges corner_edges": (lambda ids: core.face_offsets_from_corner_edges(
        CORNER_VERTS, ids, EDGES, N, len(FACE_STARTS)), np.arange(len(CORNER_VERTS)) % E, 0, E),
    "corner_quaternion_uv corner_verts": (lambda ids: core.corner_quaternion_uv(
        np.zeros((len(CORNER_VERTS), 2), np.float32), 0, ids, RESULT), CORNER_VERTS, 0, N),
    "bake corner_verts": (lambda ids: core.bake(*_with_mesh(ids)), CORNER_VERTS, 0, N),
    "find_submeshes corner_verts": (lambda ids: core.find_submeshes(*_with_mesh(ids)), CORNER_VERTS, 0, N),
    "validate_mesh corner_verts": (lambda ids: core.validate_mesh(*_with_mesh(ids)), CORNER_VERTS, 0, N),
    # Groups are labels (negative: left out), so only the wrap and the truncation apply.
    "find_close_pairs groups": (lambda ids: core.find_close_pairs(POSITIONS, 0.1, groups=ids), SV, None, None),
}


def _spoiled(valid, lowest, limit):
    """(what, index array) pairs, each with one bad element among valid ones (the last: some
    functions stop at the first bad index, the wrapped value must not be the only one read)."""
    k = len(valid) - 1
    wrapped = np.array(valid, np.int64)
    wrapped[k] += 2**32  # narrowed to int32, it would read as the valid value
    fractional = np.array(valid, np.float64)
    fractional[k] += 0.7  # truncated, it would read as the valid value
    cases = [("int64 2**32 + valid", wrapped), ("valid + 0.7", fractional)]
    if lowest is not None:
        for what, value in (("one below the lowest", lowest - 1), ("the limit", limit), ("2**40", 2**40)):
            bad = np.array(valid, np.int64)
            bad[k] = value
            cases.append((what, bad))
    return cases


@pytest.mark.parametrize("argument", sorted(INDEX_ARGUMENTS))
def test_every_index_argument_refuses_wrapped_truncated_and_out_of_range_values(argument):
    call, valid, lowest, limit = INDEX_ARGUMENTS[argument]
    call(np.ascontiguousarray(valid, np.int32))  # the valid indices are taken
    for what, bad in _spoiled(valid, lowest, limit):
        with pytest.raises(ValueError) as refused:
            call(bad)
        message = str(refused.value)
        assert "\n" not in message and len(message) < 300, (argument, what, message)


def test_box_hierarchy_refuses_bad_sizes_origins_and_turns_for_every_rule():
    """Negative or NaN half-extents, NaN or infinite origins and quaternions: none comes out of a
    bake, and each made a box silently hold nothing (or the searches compare every pair)."""
    given = np.full(S, -1)
    for rule in core.HIERARCHY_RULES:
        for which, bad, message in [(2, v, "half-extent .*: half-extents must be 0 or more") for v in (-1.0, -1e-300, np.nan)] + [
                (0, v, "origin coordinate .*: origins must be finite") for v in (np.nan, np.inf, -np.inf)] + [
                (1, v, "quaternion component .*: quaternions must be finite") for v in (np.nan, np.inf)]:
            boxes = [RESULT.origins.copy(), RESULT.quaternions.copy(), RESULT.half_extents.copy()]
            boxes[which][2, 1] = bad
            with pytest.raises(ValueError, match="box 2 has " + message):
                core.box_hierarchy(*boxes, rule, given)
        half = RESULT.half_extents.copy()
        half[2] = [0.0, np.inf, 1.0]  # zero and infinite sizes are sizes
        core.box_hierarchy(RESULT.origins, RESULT.quaternions, half, rule, given)

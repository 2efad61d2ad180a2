"""The submesh tools' core (boxmarch.core, no Blender): close pairs, select across, duplicates,
merge plans and UV packing on constructed inputs whose right answer is known."""
import numpy as np
import pytest

from boxmarch import core, scenes


def brute_pairs(points, radius):
    p = points.astype(np.float64)
    d2 = ((p[:, None, :] - p[None, :, :]) ** 2).sum(-1)
    i, j = np.nonzero(np.triu(d2 <= radius * radius, 1))
    return np.stack([i, j], 1).astype(np.uint32)


@pytest.mark.parametrize("radius", [0.0, 1e-3, 0.02, 0.3])
def test_hash_and_kdtree_find_exactly_the_brute_force_pairs(radius):
    rng = np.random.default_rng(5)
    # a uniform cloud, a dense cluster far from it, and exact duplicates
    points = np.concatenate([rng.uniform(-1, 1, (1500, 3)), 50 + rng.normal(0, 1e-3, (300, 3))])
    points = np.concatenate([points, points[:40]]).astype(np.float32)
    truth = brute_pairs(points, radius)
    for method in ("HASH", "KDTREE"):
        assert np.array_equal(core.find_close_pairs(points, radius, method=method), truth), method


def test_pairs_straddling_cell_borders_and_zero():
    eps = 1e-4
    # Pairs 1e-9 apart around 0 and around multiples of eps (the blog post's grid borders), pairs just
    # inside and just outside eps, at small and large coordinates.
    base = np.array([0.0, eps, -eps, 3 * eps, 1.0, -7.25, 100.0])
    points, expect = [], []
    for k, b in enumerate(base):
        for gap, inside in ((1e-9, True), (eps * 0.999, True), (eps * 1.001, False)):
            a = np.array([b - gap / 2, 10.0 * k, 0.0])
            points += [a, a + [gap, 0.0, 0.0]]
            expect.append(inside)
    points = np.array(points, np.float32)
    found = {tuple(p) for p in core.find_close_pairs(points, eps)}
    for n, inside in enumerate(expect):
        i, j = 2 * n, 2 * n + 1
        true_gap = np.linalg.norm(points[i].astype(np.float64) - points[j])
        assert ((i, j) in found) == (true_gap <= eps), (n, true_gap)
        if abs(true_gap - eps) > 1e-6 * max(1, abs(base[n // 3])):
            assert ((i, j) in found) == inside


def test_groups_filter_pairs_and_negative_groups_leave_points_out():
    points = np.zeros((4, 3), np.float32)
    groups = np.array([0, 0, 1, -1], np.int32)
    assert core.find_close_pairs(points, 0.0, groups=groups).tolist() == [[0, 2], [1, 2]]


@pytest.mark.parametrize("bad", [-1.0, np.nan, np.inf])
def test_bad_radius_is_refused(bad):
    with pytest.raises(ValueError, match="radius"):
        core.find_close_pairs(np.zeros((3, 3), np.float32), bad)
    arrays = scenes.box_arrays(np.zeros((2, 3)), 1.0, np.eye(3))
    ids, n = core.find_submeshes(*arrays)
    with pytest.raises(ValueError, match="epsilon"):
        core.select_linked_across(arrays[0], np.ones(16, bool), ids, n, bad)
    with pytest.raises(ValueError, match="tolerance"):
        core.find_duplicate_submeshes(arrays[0], ids, n, tolerance=bad)
    with pytest.raises(ValueError, match="distance"):
        core.merge_passes(arrays[0], ids, n, distance=bad)


def test_nan_positions_are_refused():
    arrays = scenes.box_arrays(np.zeros((2, 3)), 1.0, np.eye(3))
    positions = arrays[0].copy()
    positions[3, 1] = np.nan
    ids, n = core.find_submeshes(*arrays)
    with pytest.raises(ValueError, match="vertex 3"):
        core.select_linked_across(positions, np.ones(16, bool), ids, n, 1e-4)


def corner_chain(count, gap, size=1.0):
    """Axis-aligned unit boxes along the diagonal, each touching the next at one corner, the
    corners ``gap`` apart (along x)."""
    step = np.array([size + gap, size, size])
    centres = np.arange(count)[:, None] * step
    return scenes.box_arrays(centres, size, np.eye(3)), centres


# float32 storage near 5 units moves a gap by ~0.5% of 1e-4: test 2% either side
@pytest.mark.parametrize("gap, joined", [(0.0, True), (0.98e-4, True), (1.02e-4, False)])
def test_select_across_follows_chains_touching_at_corners(gap, joined):
    arrays, _ = corner_chain(6, gap)
    ids, n = core.find_submeshes(*arrays)
    selected = np.zeros(len(ids), bool)
    selected[2] = True  # one vertex of the first box
    mask, count = core.select_linked_across(arrays[0], selected, ids, n, 1e-4)
    assert count == (6 if joined else 1)
    assert mask.sum() == 8 * count


def test_select_across_joins_exactly_the_pairs_within_epsilon_anywhere():
    # The blog post's grid joined 427 of 500 pairs 1e-5 apart; here every pair within eps is joined
    # and none beyond, wherever the pair lies (random positions, many near cell borders).
    rng = np.random.default_rng(2)
    count, eps = 500, 1e-4
    centres = rng.uniform(-50, 50, (count, 3))
    first = scenes.box_arrays(centres, 0.5, np.eye(3))
    close = rng.normal(size=(count, 3))
    close *= (rng.uniform(0.1, 0.9, count) * eps / np.linalg.norm(close, axis=1))[:, None]
    # the second box's lowest corner sits next to the first box's highest corner
    second = scenes.box_arrays(centres + 0.5 + close, 0.5, np.eye(3))
    positions = np.concatenate([first[0], second[0]])
    faces = np.concatenate([first[2], second[2] + len(first[4])])
    arrays = (positions, np.concatenate([first[1], second[1] + 8 * count]), faces,
              np.concatenate([first[3], second[3]]), np.concatenate([first[4], second[4] + 8 * count]))
    ids, n = core.find_submeshes(*arrays)
    selected = np.zeros(len(positions), bool)
    selected[: 8 * count : 8] = True  # one vertex of every first box
    gap = np.linalg.norm(positions[7: 8 * count: 8].astype(np.float64) - positions[8 * count:: 8], axis=1)
    mask, selected_count = core.select_linked_across(positions, selected, ids, n, eps)
    assert selected_count == count + np.count_nonzero(gap <= eps)
    assert np.array_equal(mask[8 * count:: 8].astype(bool), gap <= eps)


def test_select_linked_submeshes_selects_whole_submeshes():
    arrays = scenes.box_arrays(np.arange(4)[:, None] * [3.0, 0, 0], 1.0, np.eye(3))
    ids, n = core.find_submeshes(*arrays)
    selected = np.zeros(32, bool)
    selected[[9, 30]] = True
    mask, count = core.select_linked_submeshes(selected, ids, n)
    assert count == 2
    assert mask.nonzero()[0].tolist() == list(range(8, 16)) + list(range(24, 32))


def boxes_with_copies(count, jitter, seed=0, permute=True):
    """``count`` random boxes followed by a copy of each whose vertices move by exactly
    ``jitter`` in random directions (and come in shuffled order)."""
    rng = np.random.default_rng(seed)
    (positions, edges, starts, sizes, corners), _, _, _ = scenes.random_boxes(count, seed=seed, spread=20)
    order = np.concatenate([rng.permutation(8) + 8 * b for b in range(count)]) if permute else np.arange(8 * count)
    direction = rng.normal(size=(8 * count, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    copy = (positions.astype(np.float64)[order] + jitter * direction).astype(np.float32)
    inverse = np.argsort(order)
    arrays = (np.concatenate([positions, copy]), np.concatenate([edges, inverse[edges] + 8 * count]).astype(np.int32),
              np.concatenate([starts, starts + 24 * count]).astype(np.int32), np.concatenate([sizes, sizes]),
              np.concatenate([corners, inverse[corners] + 8 * count]).astype(np.int32))
    return arrays


# float32 storage at 20 units moves a vertex by ~1e-6: test 5% either side of the tolerance
@pytest.mark.parametrize("jitter, expected", [(1e-5, 100), (0.95e-4, 100), (1.05e-4, 0)])
def test_dedup_finds_jittered_shuffled_copies(jitter, expected):
    arrays = boxes_with_copies(100, jitter)
    ids, n = core.find_submeshes(*arrays)
    duplicate_of, count = core.find_duplicate_submeshes(arrays[0], ids, n, tolerance=1e-4)
    # the blog post's rounding removed 35 of 100 at jitter 1e-5
    assert count == expected
    if expected:
        assert np.array_equal(duplicate_of, np.r_[np.full(100, -1), np.arange(100)])


def test_dedup_near_zero_and_cell_borders():
    # Copies straddling 0 and multiples of the tolerance, 1e-9 away.
    tol = 1e-4
    centres = np.array([[0.0, 0, 0], [tol, 0, 5], [-3 * tol, 5, 0]])
    a = scenes.box_arrays(centres, 0.5, np.eye(3))
    b = scenes.box_arrays(centres + 1e-9, 0.5, np.eye(3))
    arrays = (np.concatenate([a[0], b[0]]), np.concatenate([a[1], b[1] + 24]), np.concatenate([a[2], b[2] + 72]),
              np.concatenate([a[3], b[3]]), np.concatenate([a[4], b[4] + 24]))
    ids, n = core.find_submeshes(*arrays)
    duplicate_of, count = core.find_duplicate_submeshes(arrays[0], ids, n, tolerance=tol)
    assert count == 3 and duplicate_of.tolist() == [-1, -1, -1, 0, 1, 2]


def test_dedup_needs_a_one_to_one_pairing_and_respects_candidates():
    # Two 2-vertex submeshes where the greedy pairing fails and only an augmenting path works.
    positions = np.array([[1, 0, 0], [0, 0, 0], [0.1, 0, 0], [1.9, 0, 0],
                          [0, 0, 0], [0.05, 0, 0], [0.02, 0, 0]], np.float32)
    edges = np.array([[0, 1], [2, 3], [4, 5], [5, 6]], np.int32)
    empty = np.zeros(0, np.int32)
    ids, n = core.find_submeshes(positions, edges, empty, empty, empty)
    duplicate_of, count = core.find_duplicate_submeshes(positions, ids, n, tolerance=1.0)
    assert duplicate_of.tolist() == [-1, 0, -1]  # the 3-vertex submesh has a different count
    _, count = core.find_duplicate_submeshes(positions, ids, n, candidates=[1, 0, 1], tolerance=1.0)
    assert count == 0


def test_dedup_large_submeshes_use_the_sorted_search():
    # 100-vertex grids: a shuffled jittered copy is found, a copy with one vertex moved is not.
    g = np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0), [0.0]), -1).reshape(-1, 3)
    edges = np.array([[i, i + 1] for i in range(99)], np.int32)
    rng = np.random.default_rng(1)
    order = rng.permutation(100)
    copy = g[order] + 3e-5
    moved = g.copy()
    moved[57, 2] += 0.01
    positions = np.concatenate([g, copy, moved]).astype(np.float32)
    inverse = np.argsort(order)
    all_edges = np.concatenate([edges, inverse[edges] + 100, edges + 200]).astype(np.int32)
    empty = np.zeros(0, np.int32)
    ids, n = core.find_submeshes(positions, all_edges, empty, empty, empty)
    duplicate_of, count = core.find_duplicate_submeshes(positions, ids, n, tolerance=1e-4)
    assert duplicate_of.tolist() == [-1, 0, -1]


def test_merge_passes_separate_touching_submeshes():
    # Boxes whose corners coincide with the next box's: a merge over both would join them.
    arrays, _ = corner_chain(4, 0.0)
    positions = arrays[0].copy()
    ids, n = core.find_submeshes(*arrays)
    # give every box one duplicated vertex pair: vertex 1 moved next to vertex 0
    positions[1::8] = positions[0::8] + 1e-5
    passes_of_vertex, passes = core.merge_passes(positions, ids, n, distance=1e-3)
    assert passes == 1  # the touching corners (7 of box i, 0 of box i+1) are not both candidates
    assert np.flatnonzero(passes_of_vertex >= 0).tolist() == [v for b in range(4) for v in (8 * b, 8 * b + 1)]
    positions[6::8] = positions[7::8] + 1e-5  # now the touching corners both have partners
    passes_of_vertex, passes = core.merge_passes(positions, ids, n, distance=1e-3)
    assert passes == 2
    assert (passes_of_vertex[0::8] == [0, 1, 0, 1]).all()
    _, passes = core.merge_passes(positions, ids, n, chosen=[1, 0, 1, 0], distance=1e-3)
    assert passes == 1


def face_island_uvs(face_count, rng):
    """Every face its own UV island: a random-sized quad at a random place in [0, 3]."""
    size = rng.uniform(0.1, 1.0, (face_count, 1, 2))
    origin = rng.uniform(0, 3, (face_count, 1, 2))
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)[None]
    return (origin + square * size).reshape(-1, 2).astype(np.float32)


def island_boxes(uv, face_count):
    quads = uv.reshape(face_count, 4, 2).astype(np.float64)
    return quads.min(1), quads.max(1)


@pytest.mark.parametrize("padding, max_per_row", [(0.0, 0), (0.002, 0), (0.01, 7)])
def test_pack_uv_rows_by_height_inside_the_square_without_overlap(padding, max_per_row):
    rng = np.random.default_rng(3)
    arrays, centres, _, _ = scenes.random_boxes(60, seed=3)
    ids, n = core.find_submeshes(*arrays)
    faces = len(arrays[2])
    uv = face_island_uvs(faces, rng)
    before_lo, before_hi = island_boxes(uv, faces)
    report = core.pack_uv_by_height(uv, *arrays, vertex_height=arrays[0][:, 2], submesh_of_vertex=ids,
                                    submesh_count=n, padding=padding, max_per_row=max_per_row)
    assert report["islands"] == faces
    lo, hi = island_boxes(uv, faces)
    assert lo.min() >= padding - 1e-6 and hi.max() <= 1 - padding + 1e-6
    # uniform scale
    assert np.allclose((hi - lo), (before_hi - before_lo) * report["scale"], atol=1e-6)
    # no two islands overlap, and at least `padding` apart on some axis
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]).max(-1)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= padding - 1e-6
    # rows: islands sharing a bottom edge; higher submeshes never sit in a lower row
    heights = arrays[0][:, 2].reshape(-1, 8).astype(np.float64)
    box_height = (heights.min(1) + heights.max(1)) / 2
    face_height = np.repeat(box_height, 6)
    bottom = np.round(lo[:, 1], 5)
    higher = face_height[:, None] > face_height[None, :]
    assert not np.any(higher & (bottom[:, None] < bottom[None, :] - 1e-5))
    if max_per_row:
        assert np.unique(bottom, return_counts=True)[1].max() <= max_per_row
    # deterministic
    again = face_island_uvs(faces, np.random.default_rng(3))
    core.pack_uv_by_height(again, *arrays, vertex_height=arrays[0][:, 2], submesh_of_vertex=ids,
                           submesh_count=n, padding=padding, max_per_row=max_per_row)
    assert np.array_equal(again, uv)


def test_pack_uv_islands_share_uvs_at_shared_vertices_and_lock_overlapping():
    arrays = scenes.box_arrays(np.array([[0.0, 0, 0], [0, 0, 5]]), 1.0, np.eye(3))
    ids, n = core.find_submeshes(*arrays)
    # every box's six faces laid out as one strip island: corners of a vertex share a UV
    uv = np.repeat(arrays[0][arrays[4]][:, :2], 1, 0).astype(np.float32)  # planar projection: x, y
    uv[24:] += 0.25  # box 1's island overlaps box 0's
    report = core.pack_uv_by_height(uv.copy(), *arrays, vertex_height=arrays[0][:, 2], submesh_of_vertex=ids,
                                    submesh_count=n, padding=0.01)
    assert (report["islands"], report["groups"]) == (2, 2)
    locked = uv.copy()
    report = core.pack_uv_by_height(locked, *arrays, vertex_height=arrays[0][:, 2], submesh_of_vertex=ids,
                                    submesh_count=n, padding=0.01, lock_overlapping=True)
    assert (report["islands"], report["groups"]) == (2, 1)
    # they moved together: the same offset between them, scaled
    assert np.allclose(locked[24:] - locked[:24], (uv[24:] - uv[:24]) * report["scale"], atol=1e-6)


def test_pack_uv_bad_input_writes_nothing():
    arrays = scenes.box_arrays(np.zeros((3, 3)) + np.arange(3)[:, None], 1.0, np.eye(3))
    ids, n = core.find_submeshes(*arrays)
    uv = face_island_uvs(18, np.random.default_rng(0))
    kwargs = dict(vertex_height=arrays[0][:, 2], submesh_of_vertex=ids, submesh_count=n)
    bad = uv.copy()
    bad[5, 0] = np.nan
    before = bad.copy()
    with pytest.raises(ValueError, match="NaN"):
        core.pack_uv_by_height(bad, *arrays, **kwargs)
    assert np.array_equal(bad, before, equal_nan=True)
    before = uv.copy()
    with pytest.raises(ValueError, match="padding"):
        core.pack_uv_by_height(uv, *arrays, padding=0.5, **kwargs)
    with pytest.raises(ValueError, match="no room"):
        core.pack_uv_by_height(uv, *arrays, padding=0.3, **kwargs)
    with pytest.raises(ValueError, match="no face"):
        core.pack_uv_by_height(uv, *arrays, face_mask=np.zeros(18, bool), **kwargs)
    assert np.array_equal(uv, before)
    partial = uv.copy()
    mask = np.zeros(18, bool)
    mask[:6] = True
    core.pack_uv_by_height(partial, *arrays, face_mask=mask, **kwargs)
    assert np.array_equal(partial[24:], uv[24:])  # unselected faces untouched


def test_merge_targets_follow_blenders_rule():
    # Blender 5.0's Merge by Distance (seen): two vertices merge into the lower index, three or
    # more into the one nearest their centroid; the target moves to the centroid.
    positions = np.array([[0, 0, 0], [5, 0, 0], [0.02, 0, 0], [0.01, 0, 0], [5.01, 0, 0], [9, 9, 9]], np.float32)
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]], np.int32)
    empty = np.zeros(0, np.int32)
    ids, n = core.find_submeshes(positions, edges, empty, empty, empty)
    target, merged, count = core.merge_targets(positions, ids, n, distance=0.05)
    assert count == 3
    assert target.tolist() == [3, 1, 3, 3, 1, 5]
    assert np.allclose(merged[3], [0.01, 0, 0]) and np.allclose(merged[1], [5.005, 0, 0])
    # never across submeshes: the same points without edges are six submeshes
    ids, n = core.find_submeshes(positions, np.zeros((0, 2), np.int32), empty, empty, empty)
    assert core.merge_targets(positions, ids, n, distance=0.05)[2] == 0


def test_weld_drops_collapsed_corners_faces_and_edges():
    # a quad whose corners 0 and 1 merge becomes a triangle; a triangle of the same two becomes
    # nothing; a quad whose opposite corners merge needs Blender's split
    positions = np.zeros((6, 3), np.float32)
    quad = [0, 1, 2, 3]
    arrays = (positions, np.array([[0, 1], [1, 2], [2, 3], [3, 0], [1, 4], [4, 0]], np.int32),
              np.array([0, 4], np.int32), np.array([4, 3], np.int32), np.array(quad + [0, 1, 4], np.int32))
    target = np.array([0, 0, 2, 3, 4, 5], np.int32)
    w = core.weld(*arrays, target)
    assert not w["incomplete"]
    assert w["vertex_source"].tolist() == [0, 2, 3, 4, 5]
    assert w["face_source"].tolist() == [0] and w["corner_verts"].tolist() == [0, 1, 2]
    assert w["edges"].tolist() == [[0, 1], [1, 2], [2, 0], [0, 3]]
    assert w["corner_edges"].tolist() == [0, 1, 2]
    # with Blender's corner edges the new ones come by lookup, with the same result
    by_lookup = core.weld(*arrays, target, corner_edges=np.array([0, 1, 2, 3, 0, 4, 5], np.int32))
    assert all(np.array_equal(by_lookup[k], w[k]) for k in w if k != "incomplete")
    split = core.weld(*arrays, np.array([0, 1, 0, 3, 4, 5], np.int32))
    assert split["incomplete"]

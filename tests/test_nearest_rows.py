"""core.nearest_rows (cpp/src/nearest_points.cpp, a grid searched in rings) and
core.parents_by_bone against the definitions written out here: the nearest row is the argmin
over the candidates of the squared coordinate differences summed in float64 (first row on
ties), and a box's parent under the BONES rule is that nearest box among the boxes of its
bone's nearest ancestor bone holding one, found box by box."""
import numpy as np
import pytest

from boxmarch import core
from boxmarch.native import _core


def reference_nearest(points, candidates):
    points, candidates = np.asarray(points, np.float64), np.asarray(candidates, np.float64)
    return ((points[:, None, :] - candidates[None, :, :]) ** 2).sum(axis=2).argmin(axis=1)


def wrong_rows(found, points, candidates):
    """The points whose found row is not the reference's."""
    return np.flatnonzero(np.asarray(found) != reference_nearest(points, candidates))


def clustered(rng, count, centres, spread):
    return centres[rng.integers(0, len(centres), count)] + rng.normal(0, spread, (count, 3))


def scenes(rng):
    """(name, points, candidates): the cases that stress a ring search."""
    lattice = np.stack(np.meshgrid(*[np.arange(6.0)] * 3), -1).reshape(-1, 3)
    far = np.array([[0, 0, 0], [1e6, 0, 0], [0, -1e6, 3e5]])
    yield "random", rng.uniform(-1, 1, (3000, 3)), rng.uniform(-1, 1, (2000, 3))
    yield "points outside the candidates", rng.uniform(-50, 50, (2000, 3)), rng.uniform(-1, 1, (500, 3))
    # Repeated candidate rows and points on them: ties go to the lowest row.
    repeated = rng.uniform(-1, 1, (50, 3))[rng.integers(0, 50, 900)]
    yield "repeated candidates", np.concatenate([repeated[:300], rng.uniform(-1, 1, (300, 3))]), repeated
    # Whole-number points half-way between lattice points: many exactly equal distances.
    yield "equal distances", rng.integers(0, 10, (2000, 3)) / 2.0, lattice[rng.permutation(len(lattice))]
    yield "one candidate", rng.uniform(-5, 5, (100, 3)), np.array([[0.5, 0.25, 0.0]])
    yield "far-apart clusters", clustered(rng, 3000, far, 1.0), clustered(rng, 1500, far, 1.0)
    yield "far-apart sparse candidates", clustered(rng, 2000, far, 10.0), far
    yield "large coordinates", clustered(rng, 1000, far * 1e80, 1e79), clustered(rng, 1000, far * 1e80, 1e79)
    yield "tiny coordinates", rng.uniform(-1e-300, 1e-300, (500, 3)), rng.uniform(-1e-300, 1e-300, (400, 3))
    yield "a line", np.linspace(0, 1, 3000)[:, None] * [1, 2, 3], np.linspace(0, 1, 700)[:, None] * [1, 2, 3.0001]


def test_nearest_rows_match_the_definition():
    rng = np.random.default_rng(7)
    for name, points, candidates in scenes(rng):
        found = core.nearest_rows(points, candidates)
        assert found.dtype == np.int64 and found.shape == (len(points),), name
        assert wrong_rows(found, points, candidates).size == 0, name


def test_a_planted_wrong_row_is_caught():
    """Negative control: the comparison above must reject a result one row off."""
    rng = np.random.default_rng(3)
    points, candidates = rng.uniform(-1, 1, (500, 3)), rng.uniform(-1, 1, (400, 3))
    found = core.nearest_rows(points, candidates)
    found[123] = (found[123] + 1) % len(candidates)
    assert wrong_rows(found, points, candidates).tolist() == [123]


def test_coordinates_beyond_two_to_the_300_compare_their_scaled_squares():
    # NumPy's squares overflow to infinity there; the core squares the coordinates scaled down
    # by a power of 2 (exact), so the reference scales them the same way.
    rng = np.random.default_rng(5)
    points, candidates = rng.uniform(-1, 1, (800, 3)) * 1e306, rng.uniform(-1, 1, (600, 3)) * 1e306
    with np.errstate(over="ignore"):
        assert np.isinf(((points[:1, None] - candidates[None]) ** 2).sum(axis=2)).any()
    found = core.nearest_rows(points, candidates)
    assert wrong_rows(found, np.ldexp(points, -800), np.ldexp(candidates, -800)).size == 0


def test_rows_do_not_depend_on_the_thread_count():
    rng = np.random.default_rng(11)
    points, candidates = rng.uniform(-1, 1, (40000, 3)), rng.integers(0, 20, (3000, 3)) / 20.0
    rows = [_core.nearest_points(points, candidates, threads) for threads in (1, 2, 5)]
    assert all(np.array_equal(rows[0], r) for r in rows[1:])
    assert wrong_rows(rows[0][:4000], points[:4000], candidates).size == 0


def test_empty_and_non_finite_inputs():
    assert core.nearest_rows(np.zeros((0, 3)), np.zeros((0, 3))).tolist() == []
    assert core.nearest_rows(np.zeros((0, 3)), np.ones((2, 3))).tolist() == []
    with pytest.raises(ValueError, match="no candidate"):
        core.nearest_rows(np.zeros((2, 3)), np.zeros((0, 3)))
    for bad in (np.nan, np.inf):
        points = np.array([[0.0, 0, 0], [bad, 0, 0]])
        with pytest.raises(ValueError, match="finite"):
            core.nearest_rows(points, np.ones((2, 3)))
        with pytest.raises(ValueError, match="finite"):
            core.nearest_rows(np.ones((2, 3)), points)
        # The core itself: a non-finite candidate is never taken, a non-finite point gets -1.
        assert _core.nearest_points(points, np.array([[bad, 0, 0], [5.0, 0, 0]])).tolist() == [1, -1]
        assert _core.nearest_points(points, np.array([[bad, 0, 0]])).tolist() == [-1, -1]
    with pytest.raises(ValueError, match="candidates must be"):
        _core.nearest_points(np.zeros((2, 3)), np.zeros((2, 2)))


def reference_parents(box_bone, bone_parent, origins):
    parent = np.full(len(box_bone), -1, np.int32)
    for box, bone in enumerate(box_bone):
        if bone < 0:
            continue
        up = bone_parent[bone]
        while up >= 0 and up not in box_bone:
            up = bone_parent[up]
        if up < 0:
            continue
        best = None
        for other, other_bone in enumerate(box_bone):
            if other_bone == up:
                d2 = ((origins[box] - origins[other]) ** 2).sum()
                if best is None or d2 < best[0]:
                    best = (d2, other)
        parent[box] = best[1]
    return parent


def random_bone_tree(rng, bones, boxes):
    """(box_bone, bone_parent): a random tree numbered in shuffled order; a third of the bones
    hold no box and some boxes belong to no bone (-1)."""
    up = np.array([-1] + [rng.integers(-1 if rng.random() < 0.1 else 0, b) for b in range(1, bones)])
    label = rng.permutation(bones)
    bone_parent = np.full(bones, -1)
    bone_parent[label] = np.where(up >= 0, label[np.maximum(up, 0)], -1)
    holding = rng.permutation(bones)[: max(1, 2 * bones // 3)]
    box_bone = np.where(rng.random(boxes) < 0.05, -1, holding[rng.integers(0, len(holding), boxes)])
    return box_bone, bone_parent


def test_parents_by_bone_match_the_box_by_box_definition():
    rng = np.random.default_rng(13)
    for bones, boxes in ((1, 5), (4, 30), (12, 300), (40, 600)):
        for _ in range(3):
            box_bone, bone_parent = random_bone_tree(rng, bones, boxes)
            origins = np.round(rng.uniform(-3, 3, (boxes, 3)), 1)  # coarse: repeated origins, equal distances
            expected = reference_parents(box_bone, bone_parent, origins)
            found = core.parents_by_bone(box_bone, bone_parent, origins)
            assert found.dtype == np.int32 and np.array_equal(found, expected), (bones, boxes)
    # Negative control: a box given the farthest box of its parent's bone is caught.
    planted = found.copy()
    child = next(box for box in np.flatnonzero(found >= 0)
                 if len(np.unique(((origins[box_bone == box_bone[found[box]]] - origins[box]) ** 2).sum(1))) > 1)
    siblings = np.flatnonzero(box_bone == box_bone[found[child]])
    planted[child] = siblings[((origins[siblings] - origins[child]) ** 2).sum(1).argmax()]
    assert np.flatnonzero(planted != expected).tolist() == [child]


def test_parents_by_bone_refuses_bad_bones():
    with pytest.raises(ValueError, match=r"box_bone\[1\] = 2 is outside -1\.\.1"):
        core.parents_by_bone([0, 2], [-1, 0], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="cycle"):
        core.parents_by_bone([0, 0], [-1, 2, 1], np.zeros((2, 3)))

"""Per-box parameters and hierarchy in the core (cpp/src/box_params.cpp, hierarchy.cpp): the
expectations come from the inputs' construction, never from the code under test."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from boxmarch import core, scenes


def test_reduce_takes_the_majority_and_counts_disagreement():
    # submesh 0: 1, 1, 2 -> 1 (disagrees); submesh 1: 3, 3 -> 3; submesh 2: 5, 4 tie -> 5 (first);
    # submesh 3: no element -> 0.
    values = np.array([1, 1, 2, 3, 3, 5, 4], np.float32)
    ids = np.array([0, 0, 0, 1, 1, 2, 2])
    per_box, disagrees, count = core.reduce_per_submesh(values, ids, 4)
    assert per_box.tolist() == [1, 3, 5, 0]
    assert disagrees.tolist() == [True, False, True, False] and count == 2


def test_reduce_compares_whole_tuples():
    values = np.array([[1, 2, 3, 4], [1, 2, 3, 4], [1, 2, 3, 5]], np.float32)
    per_box, disagrees, count = core.reduce_per_submesh(values, [0, 0, 0], 1)
    assert per_box.tolist() == [[1, 2, 3, 4]] and count == 1


@pytest.mark.parametrize("values, ids, message", [
    (np.array([1.0, np.nan], np.float32), [0, 0], "NaN"),
    (np.array([1.0, 2.0], np.float32), [0, 3], "out of range|outside"),
    (np.zeros((2, 5), np.float32), [0, 0], "components"),
])
def test_reduce_refuses_bad_input(values, ids, message):
    with pytest.raises(ValueError, match=message):
        core.reduce_per_submesh(values, ids, 2)


def test_random_is_stable_seeded_and_uniform():
    fingerprints = np.arange(1, 20001, dtype=np.uint32) * np.uint32(2654435761)
    a, b = core.box_random(fingerprints, 7), core.box_random(fingerprints, 7)
    assert np.array_equal(a, b)
    other_seed = core.box_random(fingerprints, 8)
    assert np.mean(a == other_seed) < 0.01
    assert a.min() >= 0.0 and a.max() < 1.0
    assert np.all(a * 2**24 == np.round(a * 2**24))  # multiples of 2^-24: exact in float32
    # 20000 draws: the mean of U(0, 1) within 5 standard errors (0.0020 each), ten equal bins within 15 %
    assert abs(a.mean() - 0.5) < 0.0102
    bins = np.bincount((a * 10).astype(int), minlength=10)
    assert bins.min() > 1700 and bins.max() < 2300


def test_random_survives_a_rebake_of_an_unchanged_box():
    arrays, centres, sizes, rotations = scenes.random_boxes(20, seed=3)
    first = core.bake(*arrays)
    moved = list(arrays)
    moved[0] = arrays[0].copy()
    moved[0][8 * 5:8 * 6] += np.float32(0.25)  # box 5 moves; the other 19 stay
    second = core.bake(*moved)
    r1 = core.box_random(core.box_fingerprints(first.fingerprints, first.submesh_of_vertex, 20), 0)
    r2 = core.box_random(core.box_fingerprints(second.fingerprints, second.submesh_of_vertex, 20), 0)
    unchanged = np.arange(20) != 5
    assert np.array_equal(r1[unchanged], r2[unchanged])
    assert r1[5] != r2[5]
    assert len(np.unique(r1)) == 20


def identity_boxes(origins, half_extents):
    origins = np.asarray(origins, np.float64)
    return origins, np.tile(np.float32([0, 0, 0, 1]), (len(origins), 1)), np.asarray(half_extents, np.float64)


def test_chain_parents_follow_the_numbering():
    # Links along a bent line, numbered along it (as instances along a curve are).
    t = np.linspace(0, 3, 12)
    boxes = identity_boxes(np.stack([t, np.sin(t), 0 * t], 1), np.full((12, 3), 0.1))
    parent, depth, deepest = core.box_hierarchy(*boxes, rule="CHAIN")
    assert parent.tolist() == [-1] + list(range(11))
    assert depth.tolist() == list(range(12)) and deepest == 11


def test_containment_picks_the_smallest_larger_box():
    # 0: big box; 1: medium inside 0; 2: small inside 1 (and 0); 3: outside everything;
    # 4: a box turned 45 degrees about z whose corner region holds box 5's origin only in its own frame.
    origins = [[0, 0, 0], [1, 0, 0], [1.2, 0, 0], [10, 0, 0], [20, 0, 0], [20, 1.3, 0]]
    half = [[3, 3, 3], [1, 1, 1], [0.1, 0.1, 0.1], [1, 1, 1], [1, 1, 1], [0.1, 0.1, 0.1]]
    origins, q, half = identity_boxes(origins, half)
    s = np.sin(np.pi / 8)
    q[4] = [0, 0, s, np.cos(np.pi / 8)]
    parent, depth, deepest = core.box_hierarchy(origins, q, half, rule="CONTAINMENT")
    # (0, 1.3) lies outside the axis-aligned unit box but inside it turned 45 degrees (|x|+|y| <= 1.41)
    assert parent.tolist() == [-1, 0, 1, -1, -1, 4]
    assert depth.tolist() == [0, 1, 2, 0, 0, 1] and deepest == 2
    q[4] = [0, 0, 0, 1]
    assert core.box_hierarchy(origins, q, half, rule="CONTAINMENT")[0][5] == -1


@pytest.mark.parametrize("given, message", [
    ([1, 2, 0], "cycle"), ([-1, 1, 0], "own parent"), ([-1, 5, 0], "outside"), ([-1, 0.5, 0], "whole"),
])
def test_given_parents_must_form_a_tree(given, message):
    boxes = identity_boxes(np.zeros((3, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match=message):
        core.box_hierarchy(*boxes, rule="ATTRIBUTE", given_parent=np.array(given, np.float64))


def test_given_parents_and_depths():
    boxes = identity_boxes(np.zeros((5, 3)), np.ones((5, 3)))
    parent, depth, deepest = core.box_hierarchy(*boxes, given_parent=np.array([-1, 0, 1, 1, -1]))
    assert parent.tolist() == [-1, 0, 1, 1, -1] and depth.tolist() == [0, 1, 2, 2, 0] and deepest == 2
    parent, depth, _ = core.box_hierarchy(*boxes)
    assert parent.tolist() == [-1] * 5 and depth.tolist() == [0] * 5


def test_parents_by_bone_walks_past_bones_without_boxes():
    """Bones 0 <- 1 <- 2 <- 3, bone 1 holds no box: bone 2's boxes take bone 0's nearest box;
    a box of no bone (-1) and the boxes of root bone 0 are roots."""
    origins = np.array([[0, 0, 0], [5, 0, 0], [4, 0, 1], [0, 0, 2], [0, 0, 3], [9, 9, 9]], np.float64)
    box_bone = [0, 0, 2, 2, 3, -1]
    assert core.parents_by_bone(box_bone, [-1, 0, 1, 2], origins).tolist() == [-1, -1, 1, 0, 3, -1]
    # Equal distances go to the lower box number.
    assert core.parents_by_bone([0, 0, 1], [-1, 0], [[-1, 0, 0], [1, 0, 0], [0, 0, 0]]).tolist() == [-1, -1, 0]


def test_dominant_per_submesh():
    weights = np.array([[1.0, 0.0], [0.2, 0.9], [0.5, 0.5], [0.5, 0.5], [0.0, 0.0]])
    assert core.dominant_per_submesh(weights, [0, 0, 1, 1, 2], 3).tolist() == [0, 0, -1]  # 0.5 : 0.5 ties to 0
    assert core.dominant_per_submesh(weights[:2], [0, 0], 1).tolist() == [0]  # 1.2 against 0.9
    assert core.dominant_per_submesh(weights[1:2], [0], 1).tolist() == [1]


# The geometric rules against their pairwise definitions, written here in NumPy in the contract's
# double arithmetic (glm's quaternion rotation v + 2 (w (u x v) + u x (u x v)), u = -q.xyz),
# on scenes drawn to tie: origins on a small lattice (shared origins, equal distances),
# half-extents from a few values (equal volumes, nested boxes, origins on faces), quarter turns,
# some clusters 1e6 away and a few huge boxes. tests/cpp/test_hierarchy.cpp adds NaN, infinite
# and off-unit inputs.
def cross(a, b):
    return np.stack([a[..., 1] * b[..., 2] - b[..., 1] * a[..., 2], a[..., 2] * b[..., 0] - b[..., 2] * a[..., 0],
                     a[..., 0] * b[..., 1] - b[..., 0] * a[..., 1]], -1)


def definition_containment(origins, quaternions, half, tie=np.max):
    """``tie``: which of the smallest holders of equal volume is the parent (np.max: the higher
    index, as the contract says; np.min only for the negative control)."""
    n = len(origins)
    volume = half[:, 0] * half[:, 1] * half[:, 2]
    parent = np.full(n, -1)
    q = quaternions.astype(np.float64)
    for i in range(n):
        v = origins[i] - origins
        u = -q[:, :3]
        uv = cross(u, v)
        local = v + ((uv * q[:, 3:]) + cross(u, uv)) * 2
        bounds = half + 1e-6 * half.max(1)[:, None]
        index = np.arange(n)
        larger = (volume > volume[i]) | ((volume == volume[i]) & (index < i))
        holders = np.flatnonzero(np.all(np.abs(local) <= bounds, 1) & larger & (index != i))
        if len(holders):  # the smallest by volume, ties to the higher index (the lower one is larger)
            smallest = holders[volume[holders] == volume[holders].min()]
            parent[i] = tie(smallest)
    return parent


def definition_chain(origins, nearest="first"):
    """``nearest``: which of equally near earlier boxes is the parent ("first", as the contract
    says; "last" only for the negative control)."""
    parent = np.full(len(origins), -1)
    for i in range(1, len(origins)):
        v = origins[i] - origins[:i]
        distance = np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1] + v[:, 2] * v[:, 2])
        parent[i] = np.argmin(distance) if nearest == "first" else i - 1 - np.argmin(distance[::-1])
    return parent


QUARTER_TURNS = np.float32([[0, 0, 0, 1], [0, 0, np.sqrt(0.5), np.sqrt(0.5)], [np.sqrt(0.5), 0, 0, np.sqrt(0.5)],
                            [0.5, 0.5, 0.5, 0.5], [0.2, -0.4, 0.1, np.sqrt(0.79)]])


@st.composite
def tying_scenes(draw):
    n = draw(st.integers(0, 60))
    cells = st.lists(st.integers(-3, 3), min_size=3, max_size=3)
    origins = np.array([draw(cells) for _ in range(n)], np.float64).reshape(-1, 3) * draw(st.sampled_from([0.5, 1.0]))
    if n and draw(st.booleans()):
        origins[draw(st.integers(0, n - 1)):] += [1e6, 0, 0]
    sizes = st.sampled_from([0.25, 0.5, 1.0, 2.0, 4.0, 1e-4, 1e4])
    half = np.array([[draw(sizes) for _ in range(3)] for _ in range(n)], np.float64).reshape(-1, 3)
    turns = QUARTER_TURNS[[draw(st.integers(0, len(QUARTER_TURNS) - 1)) for _ in range(n)]].reshape(-1, 4)
    return origins, turns, half


@pytest.mark.slow  # 120 scenes against the quadratic definitions: about 3.5 s of CPU
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tying_scenes())
def test_geometric_rules_give_the_parents_of_their_pairwise_definitions(scene):
    origins, quaternions, half = scene
    assert core.box_hierarchy(origins, quaternions, half, rule="CONTAINMENT")[0].tolist() == \
        definition_containment(origins, quaternions, half).tolist()
    assert core.box_hierarchy(origins, quaternions, half, rule="CHAIN")[0].tolist() == \
        definition_chain(origins).tolist()


def rods_and_boxes(seed, rods=40, others=160):
    """Randomly turned long thin boxes (half-extents 100 x 0.005 x 0.005, as issue 36 timed them)
    crossing a cube of side 20 with small and random boxes: half of the small ones on a rod's axis
    (0.004 off it, so some inside, some past its ends), the rest spread in the cube, a few nested
    boxes and boxes as large as a rod at its origin."""
    rng = np.random.default_rng(seed)
    turns = rng.normal(size=(rods + others, 4))
    turns /= np.linalg.norm(turns, axis=1, keepdims=True)
    quaternions = turns.astype(np.float32)
    origins = rng.uniform(-10, 10, (rods + others, 3))
    half = np.concatenate([np.tile([100.0, 0.005, 0.005], (rods, 1)),
                           rng.uniform(0.001, 0.02, (others, 3))])
    q = quaternions[:rods].astype(np.float64)
    for k in range(others // 2):  # on rod k % rods: its local x axis in object space, t up to 120 along
        r = k % rods
        x, y, z, w = q[r]
        axis = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])
        side = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
        origins[rods + k] = origins[r] + rng.uniform(-120, 120) * axis + 0.004 * side / np.linalg.norm(side)
    half[rods + others - 5:] = [100.0, 0.005, 0.005]   # as large as a rod: ties broken by index
    half[rods + others - 10:rods + others - 5] = 30.0  # large boxes holding many origins
    return origins, quaternions, half


def from_local(quaternions):
    """Per box, the matrix taking a box-local difference to object space: the inverse of the map
    the definition applies (glm's rotation by the conjugate quaternion, a linear map whatever the
    length), shape (n, 3, 3); its columns are the local axes in object space."""
    q = quaternions.astype(np.float64)
    u, w = -q[:, :3], q[:, 3]
    skew = np.zeros((len(q), 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -u[:, 2], u[:, 1], -u[:, 0]
    skew -= skew.transpose(0, 2, 1)
    to_local = (1 - 2 * (u * u).sum(1))[:, None, None] * np.eye(3) + 2 * w[:, None, None] * skew \
        + 2 * u[:, :, None] * u[:, None, :]
    return np.linalg.inv(to_local)


def long_flat_and_nested_boxes(seed, count=180):
    """Boxes that take the k-d tree's costly paths (issue 36), among small ones placed on them:
    turned and axis-aligned long thin boxes (edges 4 to 1e4 times the others, some of zero
    thickness, some at the 4:1 ratio where the search changes its test and just below it), long
    boxes crossing one point, turned flat boxes, nested shells at one centre (sizes from a few
    values: equal volumes), coincident copies, quaternions off unit length (0.7 to 1.3); the
    small boxes lie on a long or flat box's faces, ends and corners exactly, just inside and just
    past them (1e-6 of its largest half-extent is the contract's slack), or anywhere."""
    rng = np.random.default_rng(seed)
    turns = rng.normal(size=(count, 4))
    turns /= np.linalg.norm(turns, axis=1, keepdims=True)
    turns[rng.random(count) < 0.2] = [0, 0, 0, 1]
    off_unit = rng.random(count) < 0.2
    turns[off_unit] *= rng.uniform(0.7, 1.3, (off_unit.sum(), 1))
    quaternions = turns.astype(np.float32)
    origins = rng.uniform(-10, 10, (count, 3))
    half = rng.uniform(0.001, 0.05, (count, 3))
    big = count // 3
    kind = rng.integers(0, 6, big)
    for i in range(big):
        length = rng.choice([4.0, 3.99, 4.01, 20.0, 1e4])
        if kind[i] in (0, 1, 2):  # long: x is the long local axis
            width = rng.choice([0.0, 1e-3, 0.01])
            half[i] = [max(width, 1e-3) * length if length < 5 else length, width, width * rng.choice([1.0, 0.5])]
            if kind[i] == 1:  # crossing the point (1, 2, 3)
                origins[i] = [1.0, 2.0, 3.0] - from_local(quaternions[i:i + 1])[0, :, 0] * rng.uniform(-8, 8)
        elif kind[i] == 3:  # flat: z thin
            half[i] = [rng.uniform(2, 20), rng.uniform(2, 20), rng.choice([0.0, 1e-3])]
        elif kind[i] == 4:  # shells at one centre
            origins[i] = [-2.0, 0.0, 0.0]
            half[i] = rng.choice([0.5, 1.0, 2.0], 3)
        elif i:  # a copy of an earlier box
            origins[i], half[i], quaternions[i] = origins[i - 1], half[i - 1], quaternions[i - 1]
    back = from_local(quaternions)
    for i in range(big, count):
        if rng.random() < 0.2:
            continue
        holder = rng.integers(0, big)
        local = half[holder] * rng.choice([-1.0, 0.0, 1.0], 3) * rng.choice([1.0, 0.3], 3)
        slack = 1e-6 * half[holder].max()
        local += rng.choice([0.0, -0.5, 0.5, 1.5], 3) * slack
        origins[i] = origins[holder] + back[holder] @ local
    return origins, quaternions, half


# (scene, seed, whether the scene's boxes are held as built: the scene tests what it is for)
CONTAINMENT_SCENES = (
    [(rods_and_boxes, seed, lambda parent: (parent[40:120] >= 0).sum() > 10 and (parent[40:120] < 40).sum() > 5)
     for seed in range(6)]  # rods do hold boxes
    + [(long_flat_and_nested_boxes, seed, lambda parent: (parent[60:] >= 0).sum() > 40)
       for seed in range(8)])  # the small boxes are held


@pytest.mark.parametrize("scene, seed, held", CONTAINMENT_SCENES,
                         ids=[f"{scene.__name__}-{seed}" for scene, seed, _ in CONTAINMENT_SCENES])
def test_containment_of_long_flat_and_nested_boxes_gives_the_parents_of_its_definition(scene, seed, held):
    origins, quaternions, half = scene(seed)
    parent = core.box_hierarchy(origins, quaternions, half, rule="CONTAINMENT")[0]
    assert parent.tolist() == definition_containment(origins, quaternions, half).tolist()
    assert held(parent)


def test_the_definitions_see_ties_and_nesting_and_catch_a_wrong_parent():
    # Box 1 and 2 are equal and share box 0's origin; box 3 sits in both, on box 2's face.
    origins = np.float64([[0, 0, 0], [0, 0, 0], [0, 0, 0], [1, 0, 0], [2, 0, 0]])
    half = np.float64([[4, 4, 4], [1, 1, 1], [1, 1, 1], [0.5, 0.5, 0.5], [0.5, 0.5, 0.5]])
    q = np.tile(QUARTER_TURNS[0], (5, 1))
    containment = core.box_hierarchy(origins, q, half, rule="CONTAINMENT")[0]
    assert containment.tolist() == definition_containment(origins, q, half).tolist() == [-1, 0, 1, 2, 0]
    assert core.box_hierarchy(origins, q, half, rule="CHAIN")[0].tolist() == definition_chain(origins).tolist() \
        == [-1, 0, 0, 0, 3]
    # Negative control: a rule that breaks the ties the other way is a wrong parent the comparison
    # catches here. Containment taking the lower-numbered of the equal holders 1 and 2 moves box
    # 3 to box 1 (a holder, not the smallest by the order); the chain taking the last of the
    # nearest earlier boxes moves box 2 (0 and 1 at distance 0) and box 3 (0, 1, 2 at 1).
    other_tie = definition_containment(origins, q, half, tie=np.min)
    assert np.flatnonzero(other_tie != containment).tolist() == [3] and other_tie[3] == 1
    assert np.flatnonzero(definition_chain(origins, nearest="last") != definition_chain(origins)).tolist() == [2, 3]

"""Tests of the Blender-free NumPy API ``boxmarch.core``.

Every expected value comes from ground truth that does not go through the code under test: the
box generator's own centres, sizes and rotations (``scenes.box_arrays``), or small NumPy
computations written here from the specification (quaternion algebra, bounds, the frame rule).
"""
from __future__ import annotations

import numpy as np
import pytest

from boxmarch import core, scenes
from tests.helpers.core_reference import (FACES, TIE_BAND, U32, assert_frames_valid, axis_angles, bounds_centre,
                                          decode_rgba, decoded_origins, distinct_sizes, flat_polygon, half_extents_in,
                                          house, mesh_from_polys, quat_matrix, reference_frame, shader_rotate,
                                          similar_copy, vertices_of, wedge)


def fan_triangles(face_starts, face_sizes, corner_verts):
    tris = []
    for start, size in zip(face_starts, face_sizes):
        c = corner_verts[start:start + size]
        tris.extend((c[0], c[k], c[k + 1]) for k in range(1, size - 1))
    return np.array(tris, np.int64)


# -------------------------------------------------------------------------------------------------
# Frames


def test_axis_turn_matrices_are_the_24_proper_signed_permutations():
    m = core.axis_turn_matrices()
    assert m.shape == (24, 3, 3)
    np.testing.assert_array_equal(m[0], np.eye(3))
    for t in m:
        assert set(np.abs(t).sum(0)) == {1.0} and set(np.abs(t).sum(1)) == {1.0}
        assert set(np.unique(t)) <= {-1.0, 0.0, 1.0}
        assert np.linalg.det(t) == pytest.approx(1.0)
    assert len({t.tobytes() for t in m}) == 24


def test_random_boxes_frames_are_orthonormal_right_handed_and_follow_the_box_axes():
    rng = np.random.default_rng(11)
    n = 300
    sizes = distinct_sizes(rng, n, 0.01, 1000.0)
    rotations = scenes.random_rotations(n, rng)
    centres = rng.uniform(-1, 1, (n, 3)) * sizes.max(1, keepdims=True)  # "near the origin"
    arrays = scenes.box_arrays(centres, sizes, rotations)
    r = core.bake(*arrays)
    assert (r.submesh_count, r.baked, r.degenerate) == (n, n, 0)
    assert np.all(r.sources == FACES)
    assert_frames_valid(r)
    frames = quat_matrix(r.quaternions)
    # Each local axis is parallel to one true box axis...
    for k in range(3):
        # (n, 3): angle between local axis k and each true box axis
        angles = axis_angles(frames[:, None, :, k], rotations.transpose(0, 2, 1))
        assert np.all(angles.min(1) < 1e-5)
    # ...namely the one the rule names: axis 1 = outward normal of the largest face, which is
    # the lower-indexed "-" face of the smallest size; axis 2 = "-" face of the middle size.
    order = np.argsort(sizes, axis=1)
    idx = np.arange(n)
    expected_x = -rotations[idx, :, order[:, 0]]
    expected_y = -rotations[idx, :, order[:, 1]]
    np.testing.assert_allclose(frames[:, :, 0], expected_x, atol=1e-5)
    np.testing.assert_allclose(frames[:, :, 1], expected_y, atol=1e-5)
    np.testing.assert_allclose(r.half_extents, 0.5 * np.take_along_axis(sizes, order, 1),
                               rtol=1e-5)


@pytest.mark.parametrize("sizes, first, second", [
    ((1.0, 1.0, 1.0), 0, 1),      # cube: everything ties, lowest face index wins
    ((1.0004, 1.0, 2.0), 0, 1),   # -y face 0.04% larger than -x: inside the band, -x wins
    ((1.01, 1.0, 2.0), 1, 0),     # 1% larger: outside the band, -y wins
    ((1.0, 2.0008, 2.0), 0, 1),   # second-axis tie: -y (face 2) beats the 0.04% larger -z (face 4)
    ((1.0, 2.02, 2.0), 0, 2),     # 1% larger: -z wins
])
def test_largest_face_ties_go_to_the_lowest_face_index(sizes, first, second):
    rotation = scenes.random_rotations(1, np.random.default_rng(3))[0]
    r = core.bake(*scenes.box_arrays([[0.2, -0.1, 0.3]], sizes, rotation))
    frame = quat_matrix(r.quaternions[0])
    np.testing.assert_allclose(frame[:, 0], -rotation[:, first], atol=1e-6)
    np.testing.assert_allclose(frame[:, 1], -rotation[:, second], atol=1e-6)


def test_angle_epsilon_decides_which_faces_may_give_the_second_axis():
    # Prism over a quadrilateral whose top edge is tilted by 0.05 rad: the top face is the
    # largest, the bottom face is only 0.05 rad off it.
    tilt, width, height, depth = 0.05, 4.0, 1.0, 1.5
    quad = np.array([[0, 0], [width, 0], [width, height + width * np.tan(tilt)], [0, height]])
    points = np.vstack([np.c_[quad, np.zeros(4)], np.c_[quad, np.full(4, depth)]])
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    arrays = mesh_from_polys([(points, faces)])
    for eps in (0.1, 0.01):
        r = core.bake(*arrays, angle_epsilon=eps)
        expected = reference_frame(arrays[0], faces, angle_epsilon=eps)
        np.testing.assert_allclose(quat_matrix(r.quaternions[0]), expected, atol=1e-6)
    # The two choices really differ (the test would be vacuous otherwise).
    a = reference_frame(arrays[0], faces, angle_epsilon=0.1)
    b = reference_frame(arrays[0], faces, angle_epsilon=0.01)
    assert np.abs(a - b).max() > 0.5


# -------------------------------------------------------------------------------------------------
# Decode


def far_boxes(seed, n):
    """Boxes of sizes 0.01..1000 placed up to 1000 units from the object origin."""
    rng = np.random.default_rng(seed)
    sizes = distinct_sizes(rng, n, 0.01, 1000.0)
    rotations = scenes.random_rotations(n, rng)
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    centres = directions * rng.uniform(0, 1000, (n, 1))
    centres[:5] = directions[:5] * 1000.0  # a few right at the limit
    return scenes.box_arrays(centres, sizes, rotations), centres, sizes, rotations


def test_vertex_decode_returns_the_bounds_centre_for_small_large_and_far_boxes():
    arrays, centres, sizes, rotations = far_boxes(21, 400)
    positions = arrays[0]
    r = core.bake(*arrays)
    assert_frames_valid(r)
    assert r.offsets.dtype == np.float32 and r.offsets.shape == (len(positions), 4)
    decoded = decoded_origins(r, positions)
    p64 = positions.astype(np.float64)
    half = 0.5 * sizes.max(1)
    for s in range(r.submesh_count):
        v = vertices_of(r, s)
        frame = quat_matrix(r.quaternions[s])
        truth = bounds_centre(p64[v], frame)
        err = np.linalg.norm(decoded[v] - truth, axis=1).max()
        assert err <= 1e-5 * half[s], (s, err, half[s])
        # The bounds centre of the float32-stored box is the generator's centre up to the
        # rounding of the stored coordinates (each moved by at most |x| * 2^-24 per component).
        rounding = 4.0 * np.abs(p64[v]).max() * U32
        assert np.linalg.norm(truth - centres[s]) <= rounding + 1e-5 * half[s]
        assert np.linalg.norm(r.origins[s] - truth) <= 1e-5 * half[s]
        # One alpha per submesh: 1 / largest local offset component (= largest half-extent of
        # the stored vertices; far small boxes are visibly distorted by float32 storage).
        own_half = half_extents_in(p64[v], frame)
        np.testing.assert_allclose(r.half_extents[s], own_half, rtol=0, atol=1e-6 * own_half.max())
        assert r.scales[s] == pytest.approx(1.0 / np.abs((truth - p64[v]) @ frame).max(), rel=1e-6)
        assert np.abs(own_half.max() - half[s]) <= rounding
    np.testing.assert_array_equal(r.offsets[:, 3], r.scales[r.submesh_of_vertex])
    assert np.all(np.abs(r.offsets[:, :3] - 0.5) <= 0.5 + 1e-6)


def test_decode_is_exact_at_random_points_inside_every_triangle():
    arrays, centres, sizes, rotations = far_boxes(22, 60)
    positions, _, face_starts, face_sizes, corner_verts = arrays
    r = core.bake(*arrays)
    tris = fan_triangles(face_starts, face_sizes, corner_verts)
    rng = np.random.default_rng(0)
    b = rng.dirichlet(np.ones(3), (len(tris), 4))  # 4 interior points per triangle
    p64 = positions.astype(np.float64)
    x = np.einsum("tkc,tcj->tkj", b, p64[tris])
    rgba = np.einsum("tkc,tcj->tkj", b, r.offsets.astype(np.float64)[tris])
    sub = r.submesh_of_vertex[tris[:, 0]]
    decoded = x + shader_rotate(decode_rgba(rgba), r.quaternions[sub][:, None, :])
    truths = np.array([bounds_centre(p64[vertices_of(r, s)], quat_matrix(r.quaternions[s]))
                       for s in range(r.submesh_count)])
    err = np.linalg.norm(decoded - truths[sub][:, None, :], axis=2).max(1)
    assert np.all(err <= 1e-5 * 0.5 * sizes.max(1)[sub])


def test_mean_origin_decodes_to_the_mean_of_the_stored_vertices():
    arrays, centres, sizes, rotations = far_boxes(23, 100)
    # Make the vertex mean differ from the bounds centre: push one corner of every box out.
    positions = arrays[0].copy()
    positions[::8] += (0.3 * (positions[::8] - centres)).astype(np.float32)
    arrays = (positions,) + arrays[1:]
    r = core.bake(*arrays, origin="MEAN")
    decoded = decoded_origins(r, positions)
    p64 = positions.astype(np.float64)
    for s in range(r.submesh_count):
        v = vertices_of(r, s)
        mean = p64[v].mean(0)
        tol = 1e-5 * 0.65 * sizes[s].max()
        assert np.linalg.norm(decoded[v] - mean, axis=1).max() <= tol
        assert np.linalg.norm(r.origins[s] - mean) <= tol
        centre = bounds_centre(p64[v], quat_matrix(r.quaternions[s]))
        assert np.linalg.norm(mean - centre) > 1e-3 * sizes[s].max()  # not vacuous


def test_reported_float_error_matches_an_independent_decode():
    # Float decode errors are ~1e-7 of the box while the coordinates are up to 1000: the
    # absolute-coordinate arithmetic here cancels ~1e-13, so agreement is only to ~1e-4 here
    # (the 1e-9 agreement is checked with bytes, whose errors are large).
    arrays, *_ = far_boxes(24, 50)
    r = core.bake(*arrays)
    decoded = decoded_origins(r, arrays[0])
    err = np.linalg.norm(decoded - r.origins[r.submesh_of_vertex], axis=1)
    rel = err / r.half_extents.max(1)[r.submesh_of_vertex]
    assert r.max_error == pytest.approx(err.max(), rel=1e-4)
    assert r.max_relative_error == pytest.approx(rel.max(), rel=1e-4)
    assert 0 < r.max_relative_error < 1e-6


# -------------------------------------------------------------------------------------------------
# Copy cache


COPIES = 40


def copy_scene(seed=31, copies=COPIES, shift=20.0):
    """Many similar copies of a few prototypes. Returns (arrays, list of (prototype points,
    faces, rotation, scale, shift, kind)) in submesh order."""
    rng = np.random.default_rng(seed)
    box_faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    corners = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
    protos = [(corners * [1.0, 2.0, 3.0], box_faces, "box"), (corners * 1.5, box_faces, "box"),
              (*wedge(), "wedge"), (*house(), "house"), (*flat_polygon(), "flat")]
    polys, meta = [], []
    for points, faces, kind in protos:
        for k in range(copies):
            rotation = scenes.random_rotations(1, rng)[0] if k % 4 else np.eye(3)
            scale = [1.0, 2.0, 0.5, rng.uniform(0.2, 5.0)][k % 4]
            if k == 1:  # exact 2x copy of copy 0: same rotation and shift
                rotation, offset = meta[-1][2], meta[-1][4]
            else:
                offset = rng.uniform(-shift, shift, 3)
            polys.append((similar_copy(points, rotation, scale, offset), faces))
            meta.append((np.asarray(points, float), faces, rotation, scale, offset, kind))
    return mesh_from_polys(polys), meta


def assert_same_bake(a, b):
    for name in ("submesh_of_vertex", "fingerprints", "statuses", "sources"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_allclose(a.quaternions, b.quaternions, rtol=0, atol=1e-6)
    np.testing.assert_allclose(a.offsets, b.offsets, rtol=0, atol=1e-6)
    np.testing.assert_allclose(a.scales, b.scales, rtol=1e-6)
    scale = 1.0 + np.abs(b.origins).max()
    np.testing.assert_allclose(a.origins, b.origins, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(a.half_extents, b.half_extents, rtol=1e-6, atol=1e-12)


def test_cache_gives_the_same_bake_as_no_cache_and_each_copy_is_right():
    arrays, meta = copy_scene()
    cached = core.bake(*arrays)
    fresh = core.bake(*arrays, use_cache=False)
    assert fresh.cache_hits == 0
    assert cached.cache_hits > 0
    assert_same_bake(cached, fresh)
    assert_frames_valid(cached)
    p64 = arrays[0].astype(np.float64)
    decoded = decoded_origins(cached, arrays[0])
    for s, (points, faces, rotation, scale, offset, _kind) in enumerate(meta):
        v = vertices_of(cached, s)
        frame = quat_matrix(cached.quaternions[s])
        # The copy's frame is the prototype's frame (from the spec rule) carried along; its
        # origin, half-extents and alpha are the prototype's, moved and scaled.
        proto_frame = reference_frame(points, faces, mesh_from_polys([(points, faces)])[1])
        np.testing.assert_allclose(frame, rotation @ proto_frame, atol=2e-5)
        proto_half = half_extents_in(points, proto_frame)
        truth = rotation @ bounds_centre(points, proto_frame) * scale + offset
        h = scale * proto_half.max()
        rounding = 4 * np.abs(p64[v]).max() * U32
        assert np.linalg.norm(cached.origins[s] - truth) <= 2e-5 * h + rounding
        np.testing.assert_allclose(cached.half_extents[s], scale * proto_half, rtol=0,
                                   atol=2e-5 * h)
        assert cached.scales[s] == pytest.approx(1.0 / h, rel=2e-5)
        # And every vertex decodes to the bounds centre of the stored copy.
        own = bounds_centre(p64[v], frame)
        assert np.linalg.norm(decoded[v] - own, axis=1).max() <= 1e-5 * h
    # Copy 1 of each prototype is copy 0 (scale 1) scaled 2x with the same rotation and shift.
    for first in range(0, len(meta), COPIES):
        assert meta[first + 1][3] == 2 * meta[first][3]
        assert cached.scales[first + 1] == pytest.approx(cached.scales[first] / 2, rel=1e-5)


def test_flat_polygon_frame_uses_face_normal_and_longest_edge():
    points, faces = flat_polygon()
    rotation = scenes.random_rotations(1, np.random.default_rng(4))[0]
    arrays = mesh_from_polys([(similar_copy(points, rotation, 1.0, [1, 2, 3]), faces)])
    r = core.bake(*arrays)
    assert core.FRAME_SOURCES[r.sources[0]] == "FACE_EDGE" and r.degenerate == 1
    expected = reference_frame(arrays[0], faces, arrays[1])
    np.testing.assert_allclose(quat_matrix(r.quaternions[0]), expected, atol=1e-6)


def box_proto(sizes):
    box = scenes.box_arrays([[0, 0, 0]], sizes, np.eye(3))
    return box[0].astype(np.float64), box[4].reshape(6, 4).tolist()


@pytest.mark.parametrize("name, proto", [
    ("box 1x2x3", box_proto([1.0, 2.0, 3.0])),
    ("cube", box_proto([1.0, 1.0, 1.0])),
    ("wedge", wedge()),
    ("house", house()),
    ("flat polygon", flat_polygon()),
])
def test_similar_copies_hit_the_cache(name, proto):
    points, faces = proto
    rng = np.random.default_rng(5)
    n = 60
    polys = [(similar_copy(points, scenes.random_rotations(1, rng)[0], rng.uniform(0.5, 2),
                           rng.uniform(-10, 10, 3)), faces) for _ in range(n)]
    arrays = mesh_from_polys(polys)
    cached = core.bake(*arrays)
    # Every copy after the first may reuse its decision (a rare bucket-border miss is allowed).
    assert cached.cache_hits >= n - 5
    assert_same_bake(cached, core.bake(*arrays, use_cache=False))


def test_copies_of_a_long_wedge_hit_the_cache():
    points, faces = wedge()
    points[3:, 2] = 30.0  # largest face 1.17 x 30, runner-up 1 x 30: no tie anywhere near
    rng = np.random.default_rng(6)
    polys = [(similar_copy(points, scenes.random_rotations(1, rng)[0], 1.0, rng.uniform(-5, 5, 3)),
              faces) for _ in range(50)]
    assert core.bake(*mesh_from_polys(polys)).cache_hits > 0


def test_copies_hit_the_cache_after_many_distinct_boxes():
    rng = np.random.default_rng(12)
    n, distinct = 1000, 400
    sizes = np.array([1.0, 2.0, 3.0]) * rng.uniform(0.5, 2, (n, 1))
    sizes[:distinct] = distinct_sizes(rng, distinct, 0.1, 5.0)
    arrays = scenes.box_arrays(rng.uniform(-10, 10, (n, 3)), sizes, scenes.random_rotations(n, rng))
    r = core.bake(*arrays, threads=1)
    assert r.cache_hits >= (n - distinct) // 2


def mirrored(points, faces):
    """Negate x and re-wind every face so normals still point outward."""
    return np.asarray(points, float) * [-1, 1, 1], [f[::-1] for f in faces]


def test_mirrored_copies_decode_and_follow_their_own_geometry():
    rng = np.random.default_rng(7)
    polys = []
    for points, faces in (house(), wedge(), flat_polygon()):
        m_points, m_faces = mirrored(points, faces)
        for k in range(6):
            rotation = scenes.random_rotations(1, rng)[0]
            offset = rng.uniform(-5, 5, 3)
            scale = rng.uniform(0.5, 2.0)
            src = (points, faces) if k % 2 == 0 else (m_points, m_faces)
            polys.append((similar_copy(src[0], rotation, scale, offset), src[1]))
    arrays = mesh_from_polys(polys)
    cached = core.bake(*arrays)
    fresh = core.bake(*arrays, use_cache=False)
    assert_same_bake(cached, fresh)
    assert_frames_valid(cached)
    p64 = arrays[0].astype(np.float64)
    decoded = decoded_origins(cached, arrays[0])
    for s, (_points, faces) in enumerate(polys):
        v = vertices_of(cached, s)
        frame = quat_matrix(cached.quaternions[s])
        if len(faces) > 1:
            np.testing.assert_allclose(frame, reference_frame(p64[v] - p64[v[0]], faces), atol=1e-5)
        own = bounds_centre(p64[v], frame)
        h = cached.half_extents[s].max()
        assert np.linalg.norm(decoded[v] - own, axis=1).max() <= 1e-5 * h


def test_exactly_translated_copies_get_bit_identical_quaternions():
    rng = np.random.default_rng(8)
    rotation = scenes.random_rotations(1, rng)[0]
    proto = scenes.box_arrays([[0, 0, 0]], [0.7, 1.1, 1.9], rotation)[0].astype(np.float64)
    # Dyadic coordinates: adding integer shifts below 2^10 stays exact in float32.
    proto = np.round(proto * 4096) / 4096
    shifts = rng.integers(-1000, 1000, (1000, 3)).astype(np.float64)
    positions = (proto[None] + shifts[:, None]).reshape(-1, 3)
    assert np.array_equal(positions.astype(np.float32).astype(np.float64), positions)
    _, edges, starts, sizes, corners = scenes.box_arrays(np.zeros((1000, 3)), 1.0, np.eye(3))
    r = core.bake(positions.astype(np.float32), edges, starts, sizes, corners)
    assert r.submesh_count == 1000
    assert len(np.unique(r.quaternions, axis=0)) == 1
    assert len(np.unique(r.scales)) == 1
    assert len(np.unique(r.half_extents, axis=0)) == 1
    # Offsets of corresponding vertices are identical too, and each copy has its own origin.
    assert len(np.unique(r.offsets.reshape(1000, 8 * 4), axis=0)) == 1
    centre = bounds_centre(proto, quat_matrix(r.quaternions[0]))
    np.testing.assert_allclose(r.origins, centre + shifts, rtol=0, atol=1e-9)


@pytest.mark.parametrize("use_cache", [True, False])
def test_result_does_not_depend_on_thread_count(use_cache):
    rng = np.random.default_rng(9)
    n = 2100  # > 2 * 1024 submeshes, so two threads really split the work
    # Copies of three prototypes, interleaved (so the caches have work to share).
    protos = np.array([[1.0, 2.0, 3.0], [0.5, 0.5, 0.5], [0.3, 1.2, 0.8]])
    sizes = protos[np.arange(n) % 3] * rng.uniform(0.5, 2, (n, 1))
    arrays = scenes.box_arrays(rng.uniform(-50, 50, (n, 3)), sizes, scenes.random_rotations(n, rng))
    one = core.bake(*arrays, threads=1, use_cache=use_cache)
    two = core.bake(*arrays, threads=2, use_cache=use_cache)
    for name in ("offsets", "quaternions", "origins", "half_extents", "scales", "fingerprints",
                 "sources", "statuses"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name), err_msg=name)
    assert (one.max_error, one.max_relative_error) == (two.max_error, two.max_relative_error)
    assert (one.cache_hits > 0) == (two.cache_hits > 0) == use_cache


# -------------------------------------------------------------------------------------------------
# Degenerate submeshes


def degenerate_pieces():
    """(name, points, faces, extra edges, expected FRAME_SOURCES name)."""
    return [
        ("single vertex", [[5.0, -3.0, 2.0]], [], [], "IDENTITY"),
        ("edge", [[1.0, 1.0, 1.0], [1.5, 2.0, 0.5]], [], [(0, 1)], "ONE_AXIS"),
        ("triangle", [[0, 0, 0], [1.0, 0.2, 0.1], [0.3, 0.9, -0.2]], [[0, 1, 2]], [], "FACE_EDGE"),
        ("flat quad", [[0, 0, 2], [2.0, 0, 2], [2.0, 1.0, 2], [0, 1.0, 2]], [[0, 1, 2, 3]], [],
         "FACE_EDGE"),
        ("collinear triangle", [[0, 0, 0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]], [[0, 1, 2]], [],
         "ONE_AXIS"),
        ("coincident vertices", [[7.0, 7.0, 7.0]] * 3, [[0, 1, 2]], [], "IDENTITY"),
        ("wire tetrahedron", [[0, 0, 0], [1.0, 0, 0], [0, 1.3, 0], [0, 0, 0.8]], [],
         [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)], "EDGES"),
        ("zero-area face on a wire", [[0, 0, 0], [1.0, 0, 0], [2.0, 0, 0], [0, 1.5, 0]],
         [[0, 1, 2]], [(0, 3)], "EDGES"),
    ]


@pytest.mark.parametrize("encoding", ["FLOAT_COLOR", "BYTE_COLOR"])
def test_degenerate_submeshes_get_valid_frames_and_exact_decode(encoding):
    pieces = degenerate_pieces()
    box = scenes.box_arrays([[0, 0, 0]], [1, 2, 3], np.eye(3))
    box_points = box[0].astype(np.float64)
    box_faces = box[4].reshape(6, 4).tolist()
    polys = [(p, f, e) for _, p, f, e, _ in pieces] + [(box_points, box_faces)]
    arrays = mesh_from_polys(polys)
    r = core.bake(*arrays, encoding=encoding)
    assert r.submesh_count == len(pieces) + 1
    assert r.degenerate == len(pieces)
    names = [core.FRAME_SOURCES[k] for k in r.sources]
    assert names == [p[4] for p in pieces] + ["FACES"]
    for name in ("offsets", "quaternions", "origins", "half_extents", "scales"):
        assert np.all(np.isfinite(getattr(r, name).astype(np.float64))), name
    assert_frames_valid(r)
    p64 = arrays[0].astype(np.float64)
    decoded = decoded_origins(r, arrays[0])
    for s in range(r.submesh_count):
        v = vertices_of(r, s)
        truth = bounds_centre(p64[v], quat_matrix(r.quaternions[s]))
        h = half_extents_in(p64[v], quat_matrix(r.quaternions[s])).max()
        if encoding == "FLOAT_COLOR":
            tol = 1e-5 * h + 1e-12
        else:  # bytes cannot hold 0.5 exactly: up to 1 / (255 a) per component
            tol = np.sqrt(3) * (1 + 1e-6) / (255.0 * r.scales[s]) + 1e-5 * h
        name = pieces[s][0] if s < len(pieces) else "box"
        assert np.linalg.norm(decoded[v] - truth, axis=1).max() <= tol, name
    # Zero-extent submeshes: identity frame, zero offset (grey, alpha 1); exact as floats.
    for s in (0, 5):
        np.testing.assert_array_equal(r.quaternions[s], [0, 0, 0, 1])
        assert r.scales[s] == 1.0
        if encoding == "FLOAT_COLOR":
            np.testing.assert_array_equal(decoded[vertices_of(r, s)], p64[vertices_of(r, s)])
    # Frames that have a face normal or an edge use it as local x.
    tri = p64[vertices_of(r, 2)]
    normal = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    assert axis_angles(quat_matrix(r.quaternions[2])[:, 0], normal / np.linalg.norm(normal)) < 1e-6
    seg = p64[vertices_of(r, 1)]
    direction = (seg[1] - seg[0]) / np.linalg.norm(seg[1] - seg[0])
    assert axis_angles(quat_matrix(r.quaternions[1])[:, 0], direction) < 1e-6


# -------------------------------------------------------------------------------------------------
# Axis turns and sorting


def test_quaternion_sign_rule_for_half_turns():
    # Axis-aligned box: many turned frames are half-turns (w = 0); then the first nonzero of
    # x, y, z is positive (docs/FORMAT.md), so one frame always gives the same four numbers.
    arrays = scenes.box_arrays([[0.0, 0.0, 0.0]], [1.0, 2.0, 3.0], np.eye(3))
    turns = core.axis_turn_matrices()
    half_turns = 0
    for t in range(24):
        q = core.bake(*arrays, axis_turn=t).quaternions[0].astype(np.float64)
        assert q[3] >= 0
        if abs(q[3]) < 1e-7:
            half_turns += 1
            assert q[:3][np.abs(q[:3]) > 1e-7][0] > 0, (t, q)
        # Base frame of this box is diag(-1, -1, 1) (faces -x, -y); the turn goes on top.
        np.testing.assert_allclose(quat_matrix(q), np.diag([-1.0, -1.0, 1.0]) @ turns[t], atol=1e-7)
    assert half_turns >= 4


def test_every_axis_turn_turns_the_frame_and_keeps_decode_exact():
    arrays, centres, sizes, rotations = far_boxes(41, 30)
    base = core.bake(*arrays)
    base_frames = quat_matrix(base.quaternions)
    turns = core.axis_turn_matrices()
    for t, turn in enumerate(turns):
        r = core.bake(*arrays, axis_turn=t)
        assert_frames_valid(r)
        frames = quat_matrix(r.quaternions)
        np.testing.assert_allclose(frames, base_frames @ turn, atol=2e-6, err_msg=f"turn {t}")
        # New local axis i is old axis perm[i]: half-extents follow.
        perm = np.abs(turn).argmax(0)
        np.testing.assert_allclose(r.half_extents, base.half_extents[:, perm], rtol=1e-6)
        np.testing.assert_allclose(r.origins, base.origins, rtol=0,
                                   atol=1e-5 * base.half_extents.max())
        decoded = decoded_origins(r, arrays[0])
        err = np.linalg.norm(decoded - r.origins[r.submesh_of_vertex], axis=1)
        assert np.all(err <= 1e-5 * 0.5 * sizes.max(1)[r.submesh_of_vertex]), f"turn {t}"


@pytest.mark.parametrize("turn", [0, 7, 19])
def test_sort_axes_by_extent_orders_half_extents_before_the_turn(turn):
    arrays, centres, sizes, rotations = far_boxes(42, 60)
    base = core.bake(*arrays)
    r = core.bake(*arrays, sort_axes_by_extent=True, axis_turn=turn)
    m = core.axis_turn_matrices()[turn]
    assert_frames_valid(r)
    # Expected sorted frame: base axes by decreasing extent, third = cross of the first two.
    base_frames = quat_matrix(base.quaternions)
    p64 = arrays[0].astype(np.float64)
    base_half = np.array([half_extents_in(p64[vertices_of(base, s)], base_frames[s])
                          for s in range(base.submesh_count)])
    order = np.argsort(-base_half, axis=1)
    x = np.take_along_axis(base_frames, order[:, None, 0:1], 2)[..., 0]
    y = np.take_along_axis(base_frames, order[:, None, 1:2], 2)[..., 0]
    sorted_frames = np.stack([x, y, np.cross(x, y)], 2)
    np.testing.assert_allclose(quat_matrix(r.quaternions), sorted_frames @ m, atol=2e-6)
    unturned = r.half_extents[:, np.argsort(np.abs(m).argmax(0))]
    assert np.all(np.diff(unturned, axis=1) < 0)
    for s in range(r.submesh_count):  # half-extents of the stored vertices in the stored frame
        own = half_extents_in(p64[vertices_of(r, s)], quat_matrix(r.quaternions[s]))
        np.testing.assert_allclose(r.half_extents[s], own, rtol=0, atol=1e-6 * own.max())
    decoded = decoded_origins(r, arrays[0])
    err = np.linalg.norm(decoded - r.origins[r.submesh_of_vertex], axis=1)
    assert np.all(err <= 1e-5 * 0.5 * sizes.max(1)[r.submesh_of_vertex])


def test_sort_axes_by_extent_orders_axes_outside_the_tie_band():
    # Axis-aligned box whose unsorted local half-extents are (0.5, 0.5004, 0.5008).
    arrays = scenes.box_arrays([[0.0, 0.0, 0.0]], [1.0, 1.0008, 1.0016], np.eye(3))
    he = core.bake(*arrays, sort_axes_by_extent=True).half_extents[0]
    for i in range(3):
        for j in range(i + 1, 3):
            assert he[i] * (1 + TIE_BAND) >= he[j], (i, j, he)


# -------------------------------------------------------------------------------------------------
# Byte colours


def byte_boxes(seed, n, lo, hi, spread):
    rng = np.random.default_rng(seed)
    sizes = distinct_sizes(rng, n, 2 * lo, 2 * hi)  # largest half-extent in [lo, hi]
    centres = rng.uniform(-spread, spread, (n, 3))
    rotations = scenes.random_rotations(n, rng)
    return scenes.box_arrays(centres, sizes, rotations), centres, sizes, rotations


def test_byte_colors_decode_within_quantisation_error():
    arrays, centres, sizes, rotations = byte_boxes(51, 300, 1.0, 64.0, 500.0)
    r = core.bake(*arrays, encoding="BYTE_COLOR")
    assert r.offsets.dtype == np.uint8 and r.offsets.shape == (len(arrays[0]), 4)
    assert_frames_valid(r)
    alpha = r.offsets[:, 3].astype(np.float64) / 255.0
    assert np.all((alpha > 0) & (alpha <= 1))
    np.testing.assert_array_equal(alpha.astype(np.float32), r.scales[r.submesh_of_vertex])
    p64 = arrays[0].astype(np.float64)
    decoded_f = decode_rgba(r.offsets)
    for s in range(r.submesh_count):
        v = vertices_of(r, s)
        frame = quat_matrix(r.quaternions[s])
        truth = bounds_centre(p64[v], frame)
        assert np.linalg.norm(r.origins[s] - truth) <= 1e-5 * sizes[s].max()
        # Per component, rounding a byte moves f by at most 1 / (255 a).
        true_f = (truth - p64[v]) @ frame
        step = (1.0 + 1e-6) / (255.0 * alpha[v[0]])
        assert np.abs(decoded_f[v] - true_f).max() <= step + 1e-6 * sizes[s].max()
        decoded = p64[v] + shader_rotate(decoded_f[v], r.quaternions[s])
        rel = np.linalg.norm(decoded - truth, axis=1).max() / (0.5 * sizes[s].max())
        assert rel < 0.01


def test_reported_byte_error_matches_an_independent_decode():
    rng = np.random.default_rng(52)
    n = 200  # largest half-extents from 0.005 to 200, up to 1000 units away
    sizes = distinct_sizes(rng, n, 0.01, 400.0)
    arrays = scenes.box_arrays(rng.uniform(-1000, 1000, (n, 3)), sizes,
                               scenes.random_rotations(n, rng))
    r = core.bake(*arrays, encoding="BYTE_COLOR")
    q = r.quaternions[r.submesh_of_vertex]
    decoded = arrays[0].astype(np.float64) + shader_rotate(decode_rgba(r.offsets), q)
    err = np.linalg.norm(decoded - r.origins[r.submesh_of_vertex], axis=1)
    rel = err / r.half_extents.max(1)[r.submesh_of_vertex]
    assert r.max_error == pytest.approx(err.max(), rel=1e-9)
    assert r.max_relative_error == pytest.approx(rel.max(), rel=1e-9)


# -------------------------------------------------------------------------------------------------
# Incremental bakes and masks


def small_scene(n=12, seed=61):
    rng = np.random.default_rng(seed)
    return scenes.box_arrays(rng.uniform(-20, 20, (n, 3)), distinct_sizes(rng, n, 0.5, 3.0),
                             scenes.random_rotations(n, rng))


def test_incremental_bake_skips_unchanged_submeshes_and_rebakes_a_moved_one():
    arrays = small_scene()
    first = core.bake(*arrays)
    positions = arrays[0].copy()
    moved = 5
    positions[8 * moved:8 * moved + 8] += np.float32([3.0, -1.0, 0.5])
    offsets = first.offsets.copy()
    r = core.bake(positions, *arrays[1:], previous_fingerprints=first.fingerprints, offsets=offsets)
    assert r.offsets is offsets or np.shares_memory(r.offsets, offsets)
    assert (r.baked, r.unchanged, r.not_selected) == (1, 11, 0)
    expected = np.full(12, core.STATUS_UNCHANGED)
    expected[moved] = core.STATUS_BAKED
    np.testing.assert_array_equal(r.statuses, expected)
    np.testing.assert_array_equal(r.written, (expected == core.STATUS_BAKED).astype(np.uint8))
    mine = r.submesh_of_vertex == moved
    np.testing.assert_array_equal(offsets[~mine], first.offsets[~mine])
    np.testing.assert_array_equal(r.fingerprints[~mine], first.fingerprints[~mine])
    assert np.all(r.fingerprints[mine] != first.fingerprints[mine])
    # Every vertex, kept or rewritten, decodes to its box's centre with the quaternion of the
    # bake that wrote it (a caller keeps the old quaternions of unchanged submeshes).
    quats = np.where((r.statuses == core.STATUS_BAKED)[:, None], r.quaternions, first.quaternions)
    decoded = positions.astype(np.float64) + shader_rotate(decode_rgba(offsets),
                                                           quats[r.submesh_of_vertex])
    for s in range(12):
        v = vertices_of(r, s)
        p = positions[v].astype(np.float64)
        frame = quat_matrix(quats[s])
        err = np.linalg.norm(decoded[v] - bounds_centre(p, frame), axis=1).max()
        assert err <= 1e-5 * half_extents_in(p, frame).max()
    np.testing.assert_allclose(r.origins[moved], first.origins[moved] + [3.0, -1.0, 0.5], atol=1e-5)
    # Same geometry again: everything is unchanged.
    again = core.bake(positions, *arrays[1:], previous_fingerprints=r.fingerprints,
                      offsets=offsets.copy())
    assert (again.baked, again.unchanged) == (0, 12)


def test_fingerprints_depend_on_the_options():
    arrays = small_scene()
    first = core.bake(*arrays)
    same = core.bake(*arrays, previous_fingerprints=first.fingerprints)
    assert same.unchanged == 12
    for options in (dict(origin="MEAN"), dict(axis_turn=3), dict(sort_axes_by_extent=True),
                    dict(angle_epsilon=0.2), dict(encoding="BYTE_COLOR")):
        r = core.bake(*arrays, previous_fingerprints=first.fingerprints, **options)
        assert (r.baked, r.unchanged) == (12, 0), options


def test_mask_bakes_only_submeshes_with_a_selected_vertex():
    arrays = small_scene()
    n_vertices = len(arrays[0])
    mask = np.zeros(n_vertices, np.uint8)
    mask[8 * 3 + 6] = 1  # one vertex of box 3
    mask[8 * 9] = 255  # one vertex of box 9
    sentinel = np.full((n_vertices, 4), -7.0, np.float32)
    r = core.bake(*arrays, mask=mask, offsets=sentinel)
    assert (r.baked, r.not_selected, r.unchanged) == (2, 10, 0)
    expected = np.full(12, core.STATUS_NOT_SELECTED)
    expected[[3, 9]] = core.STATUS_BAKED
    np.testing.assert_array_equal(r.statuses, expected)
    chosen = np.isin(r.submesh_of_vertex, [3, 9])
    assert np.all(sentinel[~chosen] == -7.0)
    full = core.bake(*arrays)
    np.testing.assert_array_equal(sentinel[chosen], full.offsets[chosen])
    np.testing.assert_array_equal(r.quaternions[[3, 9]], full.quaternions[[3, 9]])
    # Fingerprints (boxmarch.h): a selected submesh gets its own (never 0); one left out keeps
    # the previous fingerprint, or 0 when there is none, so it is never taken as baked.
    np.testing.assert_array_equal(r.fingerprints[chosen], full.fingerprints[chosen])
    assert np.all(r.fingerprints[chosen] != 0) and np.all(r.fingerprints[~chosen] == 0)
    previous = np.arange(1, n_vertices + 1, dtype=np.uint32)
    again = core.bake(*arrays, mask=mask, previous_fingerprints=previous)
    np.testing.assert_array_equal(again.fingerprints[~chosen], previous[~chosen])
    np.testing.assert_array_equal(again.fingerprints[chosen], full.fingerprints[chosen])
    # The next full incremental bake re-bakes exactly the submeshes the masked bake skipped.
    after = core.bake(*arrays, previous_fingerprints=r.fingerprints)
    np.testing.assert_array_equal(after.statuses == core.STATUS_BAKED, expected != core.STATUS_BAKED)


def test_unbaked_rows_of_a_fresh_offsets_array_are_zero():
    arrays = small_scene(n=2)
    mask = np.zeros(16, np.uint8)
    mask[0] = 1
    first = core.bake(*arrays)
    for options in (dict(mask=mask), dict(previous_fingerprints=first.fingerprints)):
        poison = np.full((16, 4), np.nan, np.float32)  # freed memory numpy may hand out again
        del poison
        r = core.bake(*arrays, **options)
        unbaked = r.statuses[r.submesh_of_vertex] != core.STATUS_BAKED
        assert unbaked.any()
        assert np.all(r.offsets[unbaked] == 0), options


def test_corner_quaternion_uv_writes_only_corners_of_written_submeshes():
    arrays = small_scene()
    first = core.bake(*arrays)
    corner_verts = arrays[4]
    uv = np.full((len(corner_verts), 2), 9.0, np.float32)
    core.corner_quaternion_uv(uv, 1, corner_verts, first)
    corner_q = first.quaternions[first.submesh_of_vertex[corner_verts]]
    np.testing.assert_array_equal(uv, corner_q[:, 2:])
    mask = np.zeros(len(arrays[0]), np.uint8)
    mask[0] = 1
    partial = core.bake(*arrays, mask=mask)
    uv = np.full((len(corner_verts), 2), 9.0, np.float32)
    core.corner_quaternion_uv(uv, 0, corner_verts, partial)
    in_first = partial.submesh_of_vertex[corner_verts] == 0
    np.testing.assert_array_equal(uv[in_first],
                                  np.broadcast_to(partial.quaternions[0, :2], (in_first.sum(), 2)))
    assert np.all(uv[~in_first] == 9.0)


def test_find_submeshes_numbers_components_by_lowest_vertex():
    # A triangle, a triangle joined to an edge, and an isolated vertex, vertices interleaved.
    positions = np.zeros((8, 3), np.float32)
    positions[:, 0] = np.arange(8)
    edges = np.array([[5, 1]], np.int32)
    face_starts = np.array([0, 3], np.int32)
    face_sizes = np.array([3, 3], np.int32)
    corner_verts = np.array([6, 2, 4, 3, 5, 0], np.int32)
    ids, count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    assert count == 3
    np.testing.assert_array_equal(ids, [0, 0, 1, 0, 1, 0, 1, 2])


def test_faces_join_submeshes_with_or_without_their_edges():
    # With edges, faces only confirm the components; without, their corners must join them. Boxes
    # are shuffled (vertex order and face order) so submeshes are not runs of indices.
    (positions, edges, face_starts, face_sizes, corner_verts), _, _, _ = scenes.random_boxes(300, seed=4)
    rng = np.random.default_rng(4)
    order = rng.permutation(len(positions))
    rename = np.empty_like(order)
    rename[order] = np.arange(len(order))
    positions, edges, corner_verts = positions[order], rename[edges].astype(np.int32), rename[corner_verts].astype(np.int32)
    for mesh_edges in (edges, np.zeros((0, 2), np.int32)):
        ids, count = core.find_submeshes(positions, mesh_edges, face_starts, face_sizes, corner_verts)
        assert count == 300
        # one id per box and one box per id: the partition is the boxes
        pairs = np.unique(np.stack([ids, order // 8], axis=1), axis=0)
        assert len(pairs) == 300 and len(np.unique(pairs[:, 0])) == 300
        # numbered by lowest vertex
        lowest = np.full(count, len(ids))
        np.minimum.at(lowest, ids, np.arange(len(ids)))
        assert np.all(np.diff(lowest) > 0)


@pytest.mark.parametrize("what, index, value, message", [
    ("positions", (2000, 1), np.nan, "vertex 2000 "),
    ("corner_verts", 5000, 2400, "corner 5000 "),
    ("edges", (3000, 0), -7, "edge 3000 "),
])
def test_checks_name_the_first_bad_element_of_a_large_mesh(what, index, value, message):
    # The checks scan blocks of 1,024 values before searching one: a later bad value in the same
    # block must not hide the first.
    arrays = dict(zip(("positions", "edges", "face_starts", "face_sizes", "corner_verts"),
                      scenes.random_boxes(300, seed=5)[0]))
    bad = arrays[what].copy()
    bad[index] = value
    later = (index[0] + 40, index[1]) if isinstance(index, tuple) else index + 40
    bad[later] = value
    arrays[what] = bad
    with pytest.raises(ValueError, match=message):
        core.validate_mesh(**arrays)


def test_empty_mesh():
    z = np.zeros((0, 3), np.float32), np.zeros((0, 2), np.int32), *(np.zeros(0, np.int32),) * 3
    r = core.bake(*z)
    assert r.submesh_count == 0 and r.offsets.shape == (0, 4) and r.quaternions.shape == (0, 4)


# -------------------------------------------------------------------------------------------------
# Bad input


def _with(arrays, index, value):
    out = list(arrays)
    out[index] = value
    return out


def _set(array, where, value):
    out = array.copy()
    out[where] = value
    return out


BOX = scenes.box_arrays([[0, 0, 0], [3, 0, 0]], [1.0, 2.0, 3.0], np.eye(3))
BAD_MESHES = {  # case: (arrays, what the message must name)
    "nan coordinate": (_with(BOX, 0, _set(BOX[0], (3, 1), np.nan)), "vertex 3"),
    "inf coordinate": (_with(BOX, 0, _set(BOX[0], (15, 2), -np.inf)), "vertex 15"),
    "float64 positions": (_with(BOX, 0, BOX[0].astype(np.float64)), "positions.*float32"),
    "positions (N, 2)": (_with(BOX, 0, np.ascontiguousarray(BOX[0][:, :2])), "positions"),
    "non-contiguous positions": (_with(BOX, 0, np.asfortranarray(BOX[0])), "positions"),
    "list positions": (_with(BOX, 0, BOX[0].tolist()), "positions"),
    "edge index too large": (_with(BOX, 1, _set(BOX[1], (5, 1), 16)), "edge 5"),
    "negative edge index": (_with(BOX, 1, _set(BOX[1], (2, 0), -1)), "edge 2"),
    "int64 edges": (_with(BOX, 1, BOX[1].astype(np.int64)), "edges.*int32"),
    "corner index too large": (_with(BOX, 4, _set(BOX[4], 7, 99)), "corner 7"),
    "negative corner index": (_with(BOX, 4, _set(BOX[4], 0, -3)), "corner 0"),
    "face runs past the corners": (_with(BOX, 3, _set(BOX[3], 11, 5)), "face 11"),
    "negative face start": (_with(BOX, 2, _set(BOX[2], 0, -1)), "face 0"),
    "face with two corners": (_with(BOX, 3, _set(BOX[3], 2, 2)), "face 2"),
    "face_sizes length mismatch": (_with(BOX, 3, BOX[3][:-1].copy()), "face_sizes"),
}


@pytest.mark.parametrize("encoding", ["FLOAT_COLOR", "BYTE_COLOR"])
@pytest.mark.parametrize("case", sorted(BAD_MESHES))
def test_bad_mesh_raises_value_error_and_writes_nothing(case, encoding):
    arrays, message = BAD_MESHES[case]
    dtype = np.float32 if encoding == "FLOAT_COLOR" else np.uint8
    offsets = np.full((16, 4), 3, dtype)
    before = offsets.copy()
    with pytest.raises(ValueError, match=message):
        core.bake(*arrays, offsets=offsets, encoding=encoding)
    np.testing.assert_array_equal(offsets, before)
    with pytest.raises(ValueError, match=message):
        core.validate_mesh(*arrays)


@pytest.mark.parametrize("options, message", [
    (dict(origin="CENTRE"), "origin"),
    (dict(origin="bounds"), "origin"),
    (dict(encoding="HALF_COLOR"), "encoding"),
    (dict(angle_epsilon=0.0), "angle_epsilon"),
    (dict(angle_epsilon=-0.1), "angle_epsilon"),
    (dict(angle_epsilon=float("nan")), "angle_epsilon"),
    (dict(axis_turn=-1), "axis_turn"),
    (dict(axis_turn=24), "axis_turn"),
    (dict(mask=np.ones(15, np.uint8)), "mask"),
    (dict(mask=np.ones((16, 2), np.uint8)), "mask"),
    (dict(angle_epsilon=1e-8), "angle_epsilon"),  # cos(1e-8) is 1 in double: float noise would pick the axes
    (dict(previous_fingerprints=np.zeros(16, np.int64)), "previous_fingerprints"),
    (dict(offsets=np.zeros((16, 4), np.uint8)), "offsets"),  # wrong dtype for FLOAT_COLOR
    (dict(offsets=np.zeros((16, 3), np.float32)), "offsets"),
])
def test_bad_options_raise_value_error_and_write_nothing(options, message):
    options = dict(options)
    offsets = options.pop("offsets", None)
    if offsets is None:
        offsets = np.full((16, 4), 0.25, np.float32)
    before = offsets.copy()
    with pytest.raises(ValueError, match=message):
        core.bake(*BOX, offsets=offsets, **options)
    np.testing.assert_array_equal(offsets, before)


def test_read_only_offsets_are_rejected():
    offsets = np.zeros((16, 4), np.float32)
    offsets.flags.writeable = False
    with pytest.raises(ValueError, match="offsets"):
        core.bake(*BOX, offsets=offsets)
    assert np.all(offsets == 0)


def test_valid_mesh_passes_validation():
    core.validate_mesh(*BOX)
    ids, count = core.find_submeshes(*BOX)
    assert count == 2
    np.testing.assert_array_equal(ids, np.repeat([0, 1], 8))

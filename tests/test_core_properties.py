"""Property-based numerical stress tests of ``boxmarch.core`` (hypothesis).

Invariances (translation, any rotation, uniform scale, vertex/face/edge order), the quaternion
rules near w = 0, hard inputs (tiny and huge boxes far from the origin, nearly parallel and
zero-area faces, collinear and coincident vertices, one-face and one-edge submeshes, a submesh of
1,000,000 vertices, NaN and infinities) and the copy cache next to its tolerance. Expected values
come from the generating transforms and from the float64 reference maths in test_core.py, never
from the code under test. Every test also checks that nothing non-finite was stored.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from boxmarch import _core as bindings  # the pybind11 module: its own argument checks
from boxmarch import core, scenes
from boxmarch.formats import layouts
from tests.helpers.core_reference import (U32, assert_frames_valid, bounds_centre, decode_rgba, decoded_origins,
                                          half_extents_in, house, mesh_from_polys, newell, quat_matrix, reference_frame,
                                          similar_copy, wedge)

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
CACHE_TOLERANCE = 1e-5  # kCacheTolerance in bake.cpp: copies may deviate by this fraction of their rms radius
FACES = core.FRAME_SOURCES.index("FACES")


# -------------------------------------------------------------------------------------------------
# Strategies


@st.composite
def rotations(draw):
    """Any rotation: a unit quaternion from four normal-ish draws (hypothesis shrinks towards
    axis-aligned ones, which are the special cases)."""
    q = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4)))
    assume(np.linalg.norm(q) > 0.1)
    return layouts.quaternion_matrices((q / np.linalg.norm(q))[None])[0]


@st.composite
def half_turns(draw):
    """Rotations by pi - delta, delta in [0, 1e-6]: quaternions with w at or just above 0, where
    q and -q meet."""
    axis = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3)))
    assume(np.linalg.norm(axis) > 0.1)
    axis /= np.linalg.norm(axis)
    delta = draw(st.sampled_from([0.0, 1e-9, 1e-7, 1e-6]))
    angle = np.pi - delta
    q = np.r_[axis * np.sin(angle / 2), np.cos(angle / 2)]
    return layouts.quaternion_matrices(q[None])[0]


def clear_decisions(points, faces, strict, angle_epsilon=0.1):
    """True when the frame rule's decisions on this shape stay the same under rounding: no face
    area near the tie band's cut and no face normal near angle_epsilon. strict: no ties at all
    either (an exact tie goes to the lowest face index, so reordering faces could change it)."""
    normals, areas = map(np.array, zip(*(newell(np.asarray(points, float), f) for f in faces)))

    def clear(sizes):
        best = sizes.max()
        if strict:
            return np.sort(sizes)[-2:][0] < (1 - 3e-3) * best if len(sizes) > 1 else True
        return not np.any(np.abs(sizes - (1 - 1e-3) * best) < 2e-4 * best)

    if not clear(areas):
        return False
    first = normals[np.argmax(areas)]
    dots = np.abs(normals @ first)
    if np.any(np.abs(dots - np.cos(angle_epsilon)) < 1e-3):
        return False
    eligible = dots < np.cos(angle_epsilon)
    return not eligible.any() or clear(areas[eligible])


@st.composite
def shapes(draw, strict=False):
    """A closed shape whose frame decisions are clear (see clear_decisions): the chiral house,
    the wedge, or a box whose corners are jittered by up to 15% (non-planar quads)."""
    kind = draw(st.sampled_from(["wedge", "jittered box"] if strict else ["house", "wedge", "jittered box"]))
    if kind == "house":
        points, faces = house()
    elif kind == "wedge":
        points, faces = wedge()
    else:
        sizes = np.array(draw(st.lists(st.floats(0.3, 3.0), min_size=3, max_size=3)))
        box = scenes.box_arrays([[0, 0, 0]], sizes, np.eye(3))
        jitter = np.array(draw(st.lists(st.floats(-0.15, 0.15), min_size=24, max_size=24))).reshape(8, 3)
        points = box[0].astype(np.float64) + jitter * sizes
        faces = box[4].reshape(6, 4).tolist()
    assume(clear_decisions(points, faces, strict))
    return np.asarray(points, np.float64), faces


def assert_stored_finite(r):
    for name in ("offsets", "quaternions", "origins", "half_extents", "scales"):
        assert np.all(np.isfinite(np.asarray(getattr(r, name), np.float64))), name
    assert np.isfinite(r.max_error) and np.isfinite(r.max_relative_error)


def assert_decode_exact(r, positions, tolerance=1e-5):
    """Every vertex decodes to its submesh's bounds centre (float64, in the baked frame) within
    tolerance x its largest half-extent (absolute 1e-30 for a point)."""
    p64 = positions.astype(np.float64)
    decoded = decoded_origins(r, positions)
    for s in range(r.submesh_count):
        v = np.flatnonzero(r.submesh_of_vertex == s)
        frame = quat_matrix(r.quaternions[s])
        centre = bounds_centre(p64[v], frame)
        h = half_extents_in(p64[v] - p64[v[0]], frame).max()
        err = np.linalg.norm(decoded[v] - centre, axis=1).max()
        assert err <= tolerance * h + 1e-30, (s, err, h)


def bake_shape(points, faces, **options):
    arrays = mesh_from_polys([(points, faces)])
    return arrays, core.bake(*arrays, **options)


# -------------------------------------------------------------------------------------------------
# Invariances


@SETTINGS
@given(shape=shapes(), rotation=rotations(), scale=st.floats(1e-3, 1e3),
       shift=st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3))
def test_similarity_moves_origin_and_frame_with_the_shape_and_decode_stays_exact(shape, rotation, scale, shift):
    """Shifts up to 10 sizes keep float32 storage from reshaping the shape (far shifts are the
    hard-input test's)."""
    points, faces = shape
    shift = scale * np.array(shift)
    base_arrays, base = bake_shape(points, faces)
    moved_arrays, moved = bake_shape(similar_copy(points, rotation, scale, shift), faces)
    assert_stored_finite(moved)
    assert_frames_valid(moved)
    assert moved.sources[0] == FACES
    # The frame turns with the shape: R times the original frame (the rule's reference too).
    frame = quat_matrix(moved.quaternions[0])
    np.testing.assert_allclose(frame, rotation @ quat_matrix(base.quaternions[0]), atol=1e-5)
    np.testing.assert_allclose(frame, reference_frame(moved_arrays[0], faces), atol=1e-5)
    # Origin and half-extents move and scale with it, up to float32 storage of the vertices.
    h = scale * base.half_extents[0].max()
    rounding = 8 * (np.abs(shift).max() + scale * np.abs(points).max()) * U32
    expected_origin = rotation @ base.origins[0] * scale + shift
    assert np.linalg.norm(moved.origins[0] - expected_origin) <= 1e-5 * h + rounding
    np.testing.assert_allclose(moved.half_extents[0], scale * base.half_extents[0], atol=1e-5 * h + rounding)
    assert_decode_exact(moved, moved_arrays[0])


@SETTINGS
@given(shape=shapes(strict=True), data=st.data())
def test_vertex_face_and_edge_order_change_nothing(shape, data):
    points, faces = shape
    arrays, base = bake_shape(points, faces)
    positions, edges, face_starts, face_sizes, corner_verts = arrays
    n, f = len(positions), len(face_starts)
    new_of_old = np.array(data.draw(st.permutations(range(n))))
    face_order = data.draw(st.permutations(range(f)))
    edge_order = np.array(data.draw(st.permutations(range(len(edges)))))
    spins = data.draw(st.lists(st.integers(0, 4), min_size=f, max_size=f))  # cyclic corner shifts
    perm_positions = np.empty_like(positions)
    perm_positions[new_of_old] = positions
    corners, starts, sizes = [], [], []
    for k, old in enumerate(face_order):
        c = corner_verts[face_starts[old]:face_starts[old] + face_sizes[old]]
        c = np.roll(c, spins[k] % len(c))
        starts.append(len(corners))
        sizes.append(len(c))
        corners.extend(new_of_old[c])
    perm_edges = np.ascontiguousarray(new_of_old[edges[edge_order]][:, ::-1], np.int32)
    r = core.bake(perm_positions, perm_edges, np.array(starts, np.int32), np.array(sizes, np.int32),
                  np.array(corners, np.int32))
    assert_stored_finite(r)
    np.testing.assert_allclose(r.quaternions, base.quaternions, atol=1e-6)
    np.testing.assert_allclose(r.origins, base.origins, atol=1e-6 * base.half_extents.max())
    np.testing.assert_allclose(r.half_extents, base.half_extents, rtol=1e-6)
    np.testing.assert_allclose(r.offsets[new_of_old], base.offsets, atol=1e-6)


@SETTINGS
@given(rotation=st.one_of(rotations(), half_turns()),
       sizes=st.lists(st.floats(0.1, 10.0), min_size=3, max_size=3).filter(
           lambda s: min(abs(a / b - 1) for a, b in [(s[0], s[1]), (s[1], s[2]), (s[0], s[2])]) > 0.05),
       encoding=st.sampled_from(core.ENCODINGS))
@example(rotation=layouts.quaternion_matrices(np.array([[0.0, 0.0, 1.0, 0.0]]))[0], sizes=[1.0, 2.0, 3.0],
         encoding="FLOAT_COLOR")
@example(rotation=layouts.quaternion_matrices(np.array([[0.0, -1.0, 0.0, 0.0]]))[0], sizes=[3.0, 2.0, 1.0],
         encoding="BYTE_COLOR")
def test_quaternion_is_unit_with_w_nonnegative_and_matches_the_frame_near_w_zero(rotation, sizes, encoding):
    r = core.bake(*scenes.box_arrays([[0.5, -2.0, 1.0]], sizes, rotation), encoding=encoding)
    assert_stored_finite(r)
    assert_frames_valid(r)
    q = r.quaternions[0].astype(np.float64)
    if q[3] == 0.0:  # at w = 0, the first nonzero of x, y, z is positive
        assert q[np.flatnonzero(q[:3])[0]] > 0
    # The frame's axes are the box's face normals: axis 1 = -(axis of the smallest size),
    # axis 2 = -(axis of the middle size) (the lower-indexed "-" faces win the exact ties).
    order = np.argsort(sizes)
    frame = quat_matrix(q)
    np.testing.assert_allclose(frame[:, 0], -rotation[:, order[0]], atol=2e-6)
    np.testing.assert_allclose(frame[:, 1], -rotation[:, order[1]], atol=2e-6)


# -------------------------------------------------------------------------------------------------
# Hard inputs


@SETTINGS
@given(size=st.sampled_from([1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6]),
       distance=st.sampled_from([0.0, 1.0, 1e3, 1e5, 1e7]),
       rotation=rotations(), encoding=st.sampled_from(core.ENCODINGS))
def test_tiny_and_huge_boxes_far_from_the_origin(size, distance, rotation, encoding):
    direction = rotation[:, 0]
    sizes = size * np.array([1.0, 1.6, 2.3])
    arrays = scenes.box_arrays([direction * distance], sizes, rotation)
    r = core.bake(*arrays, encoding=encoding)
    assert_stored_finite(r)
    assert_frames_valid(r)
    if encoding == "FLOAT_COLOR":
        assert_decode_exact(r, arrays[0])
    # Where float32 storage keeps the box's shape (spacing at the distance well below its size),
    # the frame follows its faces; elsewhere the stored vertices are another shape.
    spacing = max(distance, size) * U32
    if spacing < 1e-4 * size:
        frame = quat_matrix(r.quaternions[0])
        np.testing.assert_allclose(np.abs(frame[:, 0] @ rotation[:, 0]), 1.0, atol=1e-3)
        assert r.half_extents[0].max() == pytest.approx(sizes.max() / 2, rel=1e-3)


def prism(tilt):
    """Prism over a quadrilateral whose top edge is tilted by `tilt` rad: the top face is the
    largest and the bottom face is `tilt` off it."""
    width, height, depth = 4.0, 1.0, 1.5
    quad = np.array([[0, 0], [width, 0], [width, height + width * np.tan(tilt)], [0, height]])
    points = np.vstack([np.c_[quad, np.zeros(4)], np.c_[quad, np.full(4, depth)]])
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    return points, faces


@SETTINGS
@given(tilt=st.sampled_from([0.0, 1e-9, 1e-7, 1e-4]), rotation=rotations())
def test_nearly_parallel_faces_never_give_the_second_axis(tilt, rotation):
    points, faces = prism(tilt)
    arrays, r = bake_shape(similar_copy(points, rotation, 1.0, [3.0, -1.0, 2.0]), faces)
    assert_stored_finite(r)
    assert_frames_valid(r)
    frame = quat_matrix(r.quaternions[0])
    # Axis 2 comes from a side face, nearly perpendicular to the bottom face's normal.
    bottom = rotation @ np.array([0.0, 0.0, -1.0])
    assert abs(frame[:, 1] @ bottom) < 1e-3 or abs(frame[:, 0] @ bottom) < 1e-3
    np.testing.assert_allclose(frame, reference_frame(arrays[0], faces), atol=1e-5)
    assert_decode_exact(r, arrays[0])


@pytest.mark.parametrize("tilt_over_epsilon", [1 - 1e-6, 1 - 1e-9, 1.0, 1 + 1e-9, 1 + 1e-6])
def test_faces_at_angle_epsilon_give_a_valid_frame_either_way(tilt_over_epsilon):
    points, faces = prism(0.1 * tilt_over_epsilon)
    arrays, r = bake_shape(points, faces)
    assert_stored_finite(r)
    assert_frames_valid(r)
    assert r.sources[0] == FACES
    assert_decode_exact(r, arrays[0])


def test_zero_area_faces_are_ignored():
    points, faces = wedge()
    points = np.vstack([points, [[5.0, 5.0, 5.0]]])
    # A face on three collinear vertices, one repeating a vertex, one through a far vertex.
    degenerate = faces + [[0, 3, 0], [1, 1, 4], [6, 6, 6]]
    arrays = mesh_from_polys([(points, degenerate)])
    r = core.bake(*arrays)
    expected = reference_frame(points[:6], faces)
    assert_stored_finite(r)
    np.testing.assert_allclose(quat_matrix(r.quaternions[0]), expected, atol=1e-6)
    assert_decode_exact(r, arrays[0])


@pytest.mark.parametrize("encoding", core.ENCODINGS)
def test_collinear_coincident_one_face_and_one_edge_submeshes(encoding):
    line = np.outer(np.linspace(0, 1, 5), [1.0, 2.0, 2.0]) + [4.0, 0.0, 0.0]
    pieces = [
        (line, [], [(0, 1), (1, 2), (2, 3), (3, 4)]),                 # collinear vertices
        (np.full((4, 3), 7.25), [], [(0, 1), (1, 2), (2, 3)]),        # coincident vertices
        (np.array([[0, 0, 0], [2.0, 0, 0], [0, 1.0, 0]]) + 10, [[0, 1, 2]]),  # one triangle
        (np.array([[0, 0, 0], [0, 0, 3.0]]) - 10, [], [(0, 1)]),      # one edge
        (np.array([[1.0, 1.0, 1.0]]), []),                             # one vertex
        (np.array([[0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]]) + 20, [[0, 1, 2]]),  # one zero-area face
    ]
    arrays = mesh_from_polys(pieces)
    r = core.bake(*arrays, encoding=encoding)
    assert r.submesh_count == len(pieces)
    assert_stored_finite(r)
    assert_frames_valid(r)
    names = [core.FRAME_SOURCES[s] for s in r.sources]
    assert names == ["ONE_AXIS", "IDENTITY", "FACE_EDGE", "ONE_AXIS", "IDENTITY", "ONE_AXIS"]
    frames = quat_matrix(r.quaternions)
    # The one direction a line has is axis 1; the triangle's normal is axis 1, its longest edge axis 2.
    np.testing.assert_allclose(np.abs(frames[0][:, 0] @ [1, 2, 2]) / 3, 1.0, atol=1e-6)
    np.testing.assert_allclose(np.abs(frames[2][:, 0] @ [0, 0, 1]), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.abs(frames[3][:, 0] @ [0, 0, 1]), 1.0, atol=1e-6)
    if encoding == "FLOAT_COLOR":
        assert_decode_exact(r, arrays[0])
    else:  # 8-bit: within one byte step 2 / (255 a) of each component
        decoded = decoded_origins(r, arrays[0])
        step = 2.0 / (255.0 * r.scales[r.submesh_of_vertex])
        assert np.all(np.linalg.norm(decoded - r.origins[r.submesh_of_vertex], axis=1) <= np.sqrt(3) * step)
    # Coincident and single vertices: alpha 1 (never a division by zero); offsets decode to zero
    # in float (8-bit cannot hold 0.5: it decodes to one byte step, 2/255 - 1/255 = 1/255).
    for s in (1, 4):
        v = r.submesh_of_vertex == s
        alpha = r.offsets[v][:, 3].astype(np.float64) / (255.0 if encoding == "BYTE_COLOR" else 1.0)
        np.testing.assert_array_equal(alpha, 1.0)
        expected = 0.0 if encoding == "FLOAT_COLOR" else 1.0 / 255.0
        np.testing.assert_allclose(decode_rgba(r.offsets[v]), expected, rtol=1e-12)


@pytest.mark.slow
def test_a_submesh_of_one_million_vertices():
    # A 1 x 2 x 3 box (8 corners, 6 faces) whose first corner is chained through 999,992 interior
    # points by edges: one submesh; the interior cannot change the frame or the bounds.
    rng = np.random.default_rng(0)
    rotation = scenes.random_rotations(1, rng)[0]
    sizes = np.array([1.0, 2.0, 3.0])
    box = scenes.box_arrays([[10.0, 20.0, 30.0]], sizes, rotation)
    n = 1_000_000
    interior = (rng.uniform(-0.45, 0.45, (n - 8, 3)) * sizes) @ rotation.T + [10.0, 20.0, 30.0]
    positions = np.vstack([box[0], interior.astype(np.float32)])
    chain = np.arange(7, n - 1, dtype=np.int32)
    edges = np.vstack([box[1], np.c_[chain, chain + 1]]).astype(np.int32)
    r = core.bake(positions, edges, box[2], box[3], box[4])
    assert r.submesh_count == 1 and r.sources[0] == FACES
    assert_stored_finite(r)
    frame = quat_matrix(r.quaternions[0])
    np.testing.assert_allclose(frame[:, 0], -rotation[:, 0], atol=1e-6)
    np.testing.assert_allclose(frame[:, 1], -rotation[:, 1], atol=1e-6)
    assert np.linalg.norm(r.origins[0] - [10.0, 20.0, 30.0]) <= 1e-5
    decoded = decoded_origins(r, positions)
    assert np.linalg.norm(decoded - r.origins[0], axis=1).max() <= 1e-5 * 1.5


@SETTINGS
@given(vertex=st.integers(0, 15), axis=st.integers(0, 2), value=st.sampled_from([np.nan, np.inf, -np.inf]),
       encoding=st.sampled_from(core.ENCODINGS), with_previous=st.booleans())
def test_nan_and_infinite_coordinates_are_rejected_and_nothing_is_written(vertex, axis, value, encoding, with_previous):
    arrays = list(scenes.box_arrays([[0, 0, 0], [3, 0, 0]], [1.0, 2.0, 3.0], np.eye(3)))
    arrays[0] = arrays[0].copy()
    arrays[0][vertex, axis] = value
    dtype = np.float32 if encoding == "FLOAT_COLOR" else np.uint8
    offsets = np.full((16, 4), 3, dtype)
    previous = np.arange(16, dtype=np.uint32) if with_previous else None
    with pytest.raises(ValueError, match=f"vertex {vertex} has a NaN or infinite coordinate"):
        core.bake(*arrays, offsets=offsets, encoding=encoding, previous_fingerprints=previous)
    np.testing.assert_array_equal(offsets, 3)


@pytest.mark.parametrize("call", ["vertex_count", "half"])
def test_negative_counts_and_indices_are_refused(call):
    box = scenes.box_arrays([[0, 0, 0]], [1.0, 2.0, 3.0], np.eye(3))
    if call == "vertex_count":
        corner_edges = np.zeros(24, np.int32)
        with pytest.raises(TypeError):  # a negative count is not a size_t
            bindings.face_starts_from_corner_edges(box[4], corner_edges, box[1], -1)
    else:
        uv = np.zeros((24, 2), np.float32)
        r = core.bake(*box)
        with pytest.raises(ValueError, match="half"):
            bindings.expand_corner_quaternions(uv, -1, box[4], r.submesh_of_vertex, r.quaternions)
        assert np.all(uv == 0)


# -------------------------------------------------------------------------------------------------
# Copy cache safety


def box_points(sizes):
    box = scenes.box_arrays([[0, 0, 0]], sizes, np.eye(3))
    return box[0].astype(np.float64), box[4].reshape(6, 4).tolist()


@SETTINGS
@given(tie=st.sampled_from([0.0, 0.5e-3, 0.99e-3, 1.0e-3, 1.01e-3, 2e-3]),
       deviation=st.sampled_from([0.0, 0.5, 0.9, 1.0, 1.1, 2.0, 10.0]),
       rotation=rotations(), data=st.data())
def test_cache_never_shares_a_decision_a_fresh_bake_would_not_make(tie, deviation, rotation, data):
    """Boxes whose two largest faces differ by about the tie band (the most fragile decision),
    copied by similarity transforms and moved by `deviation` times the cache's tolerance: the
    cached bake equals the bake without cache, bit for bit, for every copy."""
    points, faces = box_points([1.0, 1.0 + tie, 2.0])
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    polys = []
    for k in range(12):
        turn = rotation if k % 2 else scenes.random_rotations(1, rng)[0]
        copy = similar_copy(points, turn, rng.uniform(0.5, 2.0), rng.uniform(-20, 20, 3))
        rms = np.sqrt(((copy - copy.mean(0)) ** 2).sum(1).mean())
        nudge = rng.normal(size=copy.shape)
        nudge *= deviation * CACHE_TOLERANCE * rms / np.linalg.norm(nudge, axis=1).max()
        polys.append((copy + nudge if k > 0 else copy, faces))
    arrays = mesh_from_polys(polys)
    cached = core.bake(*arrays)
    fresh = core.bake(*arrays, use_cache=False)
    np.testing.assert_array_equal(cached.quaternions, fresh.quaternions)
    np.testing.assert_array_equal(cached.offsets, fresh.offsets)
    np.testing.assert_array_equal(cached.sources, fresh.sources)


def best_similarity_rms_residual(prototype, copy):
    """Smallest rms distance between copy and any proper rotation + uniform scale + translation
    of prototype (Umeyama's closed form). The largest per-vertex distance of any such map is at
    least this, so a copy with residual > tolerance x rms cannot fit the cache's test."""
    x = prototype - prototype.mean(0)
    y = copy - copy.mean(0)
    u, sv, vt = np.linalg.svd(y.T @ x)
    sv[-1] *= np.sign(np.linalg.det(u @ vt))
    sse = (y ** 2).sum() - sv.sum() ** 2 / (x ** 2).sum()
    return np.sqrt(max(sse, 0.0) / len(x))


@SETTINGS
@given(deviation=st.floats(1.0, 4.0), rotation=rotations(), data=st.data())
def test_copies_beyond_the_cache_tolerance_never_hit(deviation, rotation, data):
    points, faces = house()
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    copy = similar_copy(points, rotation, rng.uniform(0.5, 2.0), rng.uniform(-5, 5, 3))
    rms = np.sqrt(((copy - copy.mean(0)) ** 2).sum(1).mean())
    nudge = rng.normal(size=copy.shape)
    nudged = copy + nudge * deviation * CACHE_TOLERANCE * rms / np.sqrt((nudge ** 2).sum(1).mean())
    stored = mesh_from_polys([(points, faces), (nudged, faces)])
    # Measure on the float32 coordinates the bake sees.
    p = stored[0].astype(np.float64)
    assume(best_similarity_rms_residual(p[:9], p[9:]) > 1.01 * CACHE_TOLERANCE * rms)
    r = core.bake(*stored, threads=1)
    assert r.cache_hits == 0
    # The exact copy does hit (the test would be vacuous otherwise).
    assert core.bake(*mesh_from_polys([(points, faces), (copy, faces)]), threads=1).cache_hits == 1


@SETTINGS
@given(rotation=rotations(), shift=st.lists(st.floats(-100, 100), min_size=3, max_size=3))
def test_mirrored_copies_never_share(rotation, shift):
    points, faces = house()
    mirrored_points = points * [-1, 1, 1]
    mirrored_faces = [f[::-1] for f in faces]
    polys = [(points, faces)]
    polys += [(similar_copy(mirrored_points, rotation, 1.0, shift), mirrored_faces) for _ in range(3)]
    arrays = mesh_from_polys(polys)
    r = core.bake(*arrays, threads=1)
    # The three mirrored copies are exact copies of one another: they may share; the original
    # may not share with any of them.
    assert r.cache_hits <= 2
    assert_frames_valid(r)
    for s in range(1, 4):
        v = np.flatnonzero(r.submesh_of_vertex == s)
        p = arrays[0][v].astype(np.float64)
        np.testing.assert_allclose(quat_matrix(r.quaternions[s]), reference_frame(p - p[0], mirrored_faces), atol=1e-5)
    assert_decode_exact(r, arrays[0])


# -------------------------------------------------------------------------------------------------
# Arbitrary arrays through the Python bindings (the fuzz target's contract one layer up; run under
# ASan and UBSan by scripts/sanitize.sh)


@st.composite
def arbitrary_meshes(draw):
    """Mostly well-formed small meshes (faces laid out one after another, indices in range, grid
    coordinates so coincident and collinear vertices are common), half of them then spoiled in
    one place: an index out of range or negative, a face too small or running past the corners,
    a non-finite coordinate."""
    n = draw(st.integers(1, 10))
    coordinate = st.one_of(st.integers(-4, 4).map(float), st.floats(-4, 4), st.sampled_from([1e30, -1e-30]))
    positions = np.array(draw(st.lists(coordinate, min_size=3 * n, max_size=3 * n)), np.float32).reshape(n, 3)
    index = st.integers(0, n - 1)
    edges = np.array(draw(st.lists(st.tuples(index, index), max_size=10)), np.int32).reshape(-1, 2)
    face_sizes = np.array(draw(st.lists(st.integers(3, 5), max_size=5)), np.int32)
    face_starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]]).astype(np.int32) if len(face_sizes) else \
        np.zeros(0, np.int32)
    corner_verts = np.array(draw(st.lists(index, min_size=int(face_sizes.sum()), max_size=int(face_sizes.sum()))),
                            np.int32)
    arrays = [positions, edges, face_starts, face_sizes, corner_verts]
    spoil = draw(st.sampled_from([None, None, None, "position", "edge", "corner", "size", "start"]))
    target = {"position": 0, "edge": 1, "start": 2, "size": 3, "corner": 4}.get(spoil)
    if target is not None and arrays[target].size:
        flat = arrays[target].reshape(-1)
        at = draw(st.integers(0, flat.size - 1))
        if spoil == "position":
            flat[at] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
        elif spoil == "size":
            flat[at] = draw(st.sampled_from([-1, 0, 2, 100]))
        elif spoil == "start":
            flat[at] = draw(st.sampled_from([-1, len(corner_verts), 2**31 - 1]))
        else:
            flat[at] = draw(st.sampled_from([-1, n, 2**31 - 1, -2**31]))
    return tuple(arrays)


def valid_by_hand(positions, edges, face_starts, face_sizes, corner_verts):
    """The validation rules of docs and header, written out independently."""
    n = len(positions)
    return bool(np.all(np.isfinite(positions)) and np.all((edges >= 0) & (edges < n)) and
                np.all(face_sizes >= 3) and np.all(face_starts >= 0) and
                np.all(face_starts.astype(np.int64) + face_sizes <= len(corner_verts)) and
                np.all((corner_verts >= 0) & (corner_verts < n)))


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(mesh=arbitrary_meshes(), encoding=st.sampled_from(core.ENCODINGS), data=st.data())
def test_arbitrary_arrays_are_rejected_or_baked_validly(mesh, encoding, data):
    n = len(mesh[0])
    dtype = np.float32 if encoding == "FLOAT_COLOR" else np.uint8
    offsets = np.full((n, 4), 3, dtype)
    mask = np.array(data.draw(st.lists(st.integers(0, 1), min_size=n, max_size=n)), np.uint8)
    valid = valid_by_hand(*mesh)
    try:
        r = core.bake(*mesh, offsets=offsets, encoding=encoding, mask=mask if data.draw(st.booleans()) else None)
    except ValueError:
        assert not valid
        np.testing.assert_array_equal(offsets, 3)
        with pytest.raises(ValueError):
            core.validate_mesh(*mesh)
        return
    assert valid
    baked = r.statuses[r.submesh_of_vertex] == 0 if n else np.zeros(0, bool)
    assert_stored_finite(r)
    q = r.quaternions[r.statuses == 0].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    assert np.all(q[:, 3] >= 0)
    assert np.all(r.offsets[baked][:, 3] > 0)
    np.testing.assert_array_equal(r.offsets[~baked], 3)  # not baked: left as it was


@settings(max_examples=200, deadline=None)
@given(corner_verts=st.lists(st.integers(-2, 12), max_size=16), data=st.data())
def test_face_starts_from_arbitrary_corner_edges_never_crash(corner_verts, data):
    corner_verts = np.array(corner_verts, np.int32)
    corner_edges = np.array(data.draw(st.lists(st.integers(-2, 12), min_size=len(corner_verts),
                                               max_size=len(corner_verts))), np.int32)
    edges = np.array(data.draw(st.lists(st.integers(-2, 12), max_size=20)), np.int32)
    edges = edges[: len(edges) // 2 * 2].reshape(-1, 2)
    vertex_count = data.draw(st.integers(0, 12))
    in_range = (np.all((corner_edges >= 0) & (corner_edges < len(edges))) and
                np.all((corner_verts >= 0) & (corner_verts < vertex_count)))
    try:
        result = core.face_offsets_from_corner_edges(corner_verts, corner_edges, edges, vertex_count, face_count=2)
    except ValueError:
        assert not in_range
        return
    assert in_range
    if result is not None:
        starts, sizes = result
        assert len(starts) == 2 and np.all(sizes >= 3) and sizes.sum() + starts[0] == len(corner_verts)


def test_weld_refuses_faces_that_share_corners():
    # Two triangles over the same three corners pass validate_mesh but name 6 corners of 3: the
    # weld's outputs (sized by the input) would overflow. Found by the fuzz target under ASan.
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    arrays = (positions, np.array([[0, 1], [1, 2], [2, 0]], np.int32), np.array([0, 0], np.int32),
              np.array([3, 3], np.int32), np.array([0, 1, 2], np.int32))
    core.validate_mesh(*arrays)
    with pytest.raises(ValueError, match="faces overlap"):
        core.weld(*arrays, np.array([0, 1, 1], np.int32))

"""Hostile inputs through boxmarch.core, round 2 (issue 21): the angle_epsilon range, arguments the
NumPy API converted silently (int64 targets, 2.7 as an integer, bool masks, zero ray directions),
outputs sharing memory with inputs, and another Python thread writing the input arrays while the
core runs without the GIL. docs/CHECKS.md lists each case and what it gets."""
import inspect
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import boxmarch
from boxmarch import cli_args, core, core_boxes, core_render, core_tools, scenes
from boxmarch.formats import layouts
from tests.helpers.core_reference import decoded_origins, mesh_from_polys
from tests.hostile import race_child

HERE = Path(__file__).parent
PACKAGE_PARENT = Path(boxmarch.__file__).parent.parent
CUBE = scenes.box_arrays(np.zeros((1, 3)), [1.0, 0.6, 0.2], np.eye(3)[None])


# -------------------------------------------------------------------------------------------------
# angle_epsilon: one range, and a reported error never below the true one


def test_angle_epsilon_has_one_range_for_the_api_and_the_command_line():
    lo, hi = core.ANGLE_EPSILON_RANGE
    assert lo == float(np.float32(1e-6)) and hi == float(np.float32(1.5707963)) and hi < np.pi / 2
    offsets = np.full((8, 4), 0.25, np.float32)
    for bad in (1e-8, 1e-12, 0.0, np.nextafter(lo, 0.0), np.nextafter(hi, 2.0), np.pi / 2, float("nan")):
        with pytest.raises(ValueError, match=r"angle_epsilon must be in \[1e-06, 1.570796\] radians"):
            core.bake(*CUBE, offsets=offsets, angle_epsilon=bad)
        assert (offsets == 0.25).all()
    for good in (lo, 1e-6, 0.1, hi):
        assert core.bake(*CUBE, angle_epsilon=good).max_relative_error < 1e-6
    parser = cli_args.build_parser("", dict.fromkeys(("bake", "dedup", "merge", "pack-uv", "export", "pipeline", "demo")), "boxmarch")
    with pytest.raises(cli_args.InputError, match=r"--angle-epsilon: must be in \[1e-06, 1.570796\] radians, got 1e-8"):
        parser.parse_args(["bake", "--angle-epsilon", "1e-8"])
    assert parser.parse_args(["pipeline", "--angle-epsilon", "1e-6"]).angle_epsilon == 1e-6


def prism(tilt):
    """A prism whose largest face (the bottom, 4 x 1.5) has the top face `tilt` rad off parallel."""
    width, height, depth = 4.0, 1.0, 1.5
    quad = np.array([[0, 0], [width, 0], [width, height + width * np.tan(tilt)], [0, height]])
    points = np.vstack([np.c_[quad, np.zeros(4)], np.c_[quad, np.full(4, depth)]])
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    return points, faces


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(log_epsilon=st.floats(np.log10(core.ANGLE_EPSILON_RANGE[0]), np.log10(core.ANGLE_EPSILON_RANGE[1])),
       tilt_over_epsilon=st.sampled_from([0.0, 0.5, 1.0 - 1e-3, 1.0 + 1e-3, 1.5, 3.0]),
       quaternion=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
       shift=st.floats(0.0, 1e3), origin=st.sampled_from(core.ORIGIN_MODES), encoding=st.sampled_from(core.ENCODINGS))
def test_the_reported_decode_error_is_never_below_the_true_one(log_epsilon, tilt_over_epsilon, quaternion, shift,
                                                               origin, encoding):
    """Prisms whose two largest faces are about angle_epsilon apart (the second axis is then a
    near-cancellation), turned and moved anywhere. Truth, independent of the baked frame: with
    MEAN the origin is the vertex mean; with either origin no point is closer to all decoded
    points than half their spread. The bake's max_error must not be below either (up to double
    rounding of the coordinates)."""
    epsilon = float(np.clip(10.0 ** log_epsilon, *core.ANGLE_EPSILON_RANGE))  # the power may round outside
    points, faces = prism(min(tilt_over_epsilon * epsilon, 1.2))
    rotation = layouts.quaternion_matrices(np.asarray(quaternion)[None] / np.linalg.norm(quaternion))[0]
    points = points @ rotation.T + shift
    arrays = mesh_from_polys([(points, faces)])
    r = core.bake(*arrays, angle_epsilon=epsilon, origin=origin, encoding=encoding)
    p64 = arrays[0].astype(np.float64)
    decoded = decoded_origins(r, arrays[0])
    rounding = 1e-13 * np.abs(p64).max()
    spread = np.linalg.norm(decoded[:, None] - decoded[None], axis=-1).max()
    assert r.max_error >= spread / 2 - rounding, (r.max_error, spread / 2)
    if origin == "MEAN":
        truth = np.linalg.norm(decoded - p64.mean(0), axis=1).max()
        assert r.max_error >= truth - rounding, (r.max_error, truth)


# -------------------------------------------------------------------------------------------------
# Arguments the NumPy API converted silently


def test_weld_refuses_targets_a_cast_to_int32_would_change():
    arrays = scenes.box_arrays(np.zeros((1, 3)), 1.0, np.eye(3)[None])
    target = np.arange(8, dtype=np.int64)
    target[3] = 2**32 + 3  # wraps to 3, a valid survivor: the weld would look like a no-op
    with pytest.raises(ValueError, match=r"target\[3\] = 4294967299 is outside 0..7"):
        core.weld(*arrays, target)
    with pytest.raises(ValueError, match="target must hold integers"):
        core.weld(*arrays, np.arange(8) + 0.7)
    same = core.weld(*arrays, np.arange(8, dtype=np.int64))
    assert np.array_equal(same["vertex_source"], np.arange(8))


def reference_remove(corner_verts, face_starts, face_sizes, remove):
    """Faces kept by remove_vertices, face by face in a plain loop: (face_source, corner_source)."""
    faces, corners = [], []
    for f, (start, size) in enumerate(zip(face_starts, face_sizes)):
        run = list(range(start, start + size))
        if not any(remove[corner_verts[c]] for c in run):
            faces.append(f)
            corners += run
    return faces, corners


def test_remove_vertices_checks_faces_and_takes_them_in_any_order():
    positions, edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(
        np.array([[0.0, 0, 0], [3, 0, 0]]), 1.0, np.eye(3)[None])
    corner_edges = np.zeros(len(corner_verts), np.int32)
    remove = np.zeros(16, bool)
    remove[9] = True
    # Faces listed in reverse order of their corners: each face still owns its own corners.
    order = np.arange(len(face_starts))[::-1]
    starts, sizes = face_starts[order].copy(), face_sizes[order].copy()
    r = core.remove_vertices(positions, edges, starts, sizes, corner_verts, remove, corner_edges)
    faces, corners = reference_remove(corner_verts, starts, sizes, remove)
    assert list(r["face_source"]) == faces and list(r["corner_source"]) == corners
    assert len(r["vertex_source"]) == 15
    for bad_starts, bad_sizes, message in (
            (np.r_[face_starts[:-1], 60], face_sizes, "face 11 runs outside the corner array"),
            (np.r_[face_starts[:-1], -4], face_sizes, "face 11 runs outside the corner array"),
            (face_starts, np.r_[face_sizes[:-1], 2], "face 11 has fewer than 3 corners"),
            (np.r_[face_starts, 0], np.r_[face_sizes, 4], "faces name 52 corners but there are 48: faces overlap"),
            (face_starts, face_sizes[:-1], "face_sizes")):
        with pytest.raises(ValueError, match=message):
            core.remove_vertices(positions, edges, bad_starts.astype(np.int32), bad_sizes.astype(np.int32),
                                 corner_verts, remove, corner_edges)


def test_integer_arguments_refuse_fractions_instead_of_truncating():
    with pytest.raises(ValueError, match="axis_turn must be an integer, got 2.7"):
        core.bake(*CUBE, axis_turn=2.7)
    assert np.array_equal(core.bake(*CUBE, axis_turn=3.0).quaternions, core.bake(*CUBE, axis_turn=3).quaternions)
    with pytest.raises(ValueError, match="submesh_count must be an integer"):
        core.merge_targets(CUBE[0], np.zeros(8, np.int32), 1.5)
    with pytest.raises(ValueError, match="width must be an integer, got 2.5"):
        core.render_boxes(np.zeros((1, 3)), [[0, 0, 0, 1]], [[1, 1, 1]], np.eye(4), np.eye(4), 2.5, 4)
    with pytest.raises(ValueError, match="vertex_count must be an integer"):
        core.vertex_values_from_corners(np.zeros(3), [0, 1, 2], "3")


def test_bake_takes_a_bool_mask_like_the_tools():
    positions, *rest = scenes.box_arrays(np.array([[0.0, 0, 0], [3, 0, 0]]), 1.0, np.eye(3)[None])
    as_bool = np.arange(16) >= 8
    r = core.bake(positions, *rest, mask=as_bool)
    assert list(r.statuses) == [core.STATUS_NOT_SELECTED, core.STATUS_BAKED]
    same = core.bake(positions, *rest, mask=as_bool.astype(np.uint8))
    assert np.array_equal(r.offsets, same.offsets)


def test_corner_and_submesh_indices_out_of_range_are_named():
    with pytest.raises(ValueError, match=r"corner_verts\[1\] = 5 is outside 0..2"):
        core.vertex_values_from_corners(np.zeros(3), [0, 5, 2], 3)
    with pytest.raises(ValueError, match=r"corner_verts\[0\] = -1 is outside 0..2"):
        core.vertex_values_from_corners(np.zeros(3), [-1, 1, 2], 3)
    with pytest.raises(ValueError, match=r"submesh_of_vertex\[2\] = -1"):
        core.boxes_from_bake(np.zeros((3, 3)), np.full((3, 4), 0.5), np.tile([0, 0, 0, 1.0], (3, 1)), [0, 0, -1])


def test_a_ray_without_direction_is_refused_and_a_tiny_one_marches():
    origins = np.array([[-5.0, 0, 0], [-5.0, 0, 0]], np.float32)
    with pytest.raises(ValueError, match="ray 1 has a zero direction"):
        core.raymarch(origins, np.array([[1.0, 0, 0], [0, 0, 0]]), [1.0, 1.0, 1.0])
    # Components whose float32 squares underflow or overflow still give the direction they point in.
    r = core.raymarch(origins, np.array([[1e-30, 0, 0], [1e20, 0, 0]]), [1.0, 1.0, 1.0])
    assert r.hit.all()
    np.testing.assert_allclose(r.positions, [[-1.0, 0, 0], [-1.0, 0, 0]], atol=2e-3)


def test_offsets_sharing_memory_with_the_positions_bake_the_positions_as_passed():
    positions, *rest = scenes.box_arrays(np.array([[1.0, 2, 3], [5, 0, 0]]), [1.0, 0.6, 0.2],
                                         scenes.random_rotations(2, np.random.default_rng(2)))
    expected = core.bake(positions.copy(), *rest)
    buffer = np.zeros((16, 4), np.float32)
    shared_positions = buffer.reshape(-1)[:48].reshape(16, 3)  # the first 12 offset rows' memory
    shared_positions[:] = positions
    r = core.bake(shared_positions, *rest, offsets=buffer)
    assert r.offsets is buffer
    np.testing.assert_array_equal(r.origins, expected.origins)
    np.testing.assert_array_equal(buffer, expected.offsets)


def test_corner_quaternions_written_over_the_quaternions_they_read_are_the_quaternions_passed():
    arrays = scenes.box_arrays(np.array([[0.0, 0, 0], [3, 0, 0]]), [1.0, 0.6, 0.2],
                               scenes.random_rotations(2, np.random.default_rng(9)))
    r = core.bake(*arrays)
    corner_verts = arrays[4]
    expected = np.zeros((len(corner_verts), 2), np.float32)
    core.corner_quaternion_uv(expected, 1, corner_verts, r, write_all=True)
    corner_uv = np.zeros((len(corner_verts), 2), np.float32)
    shared = corner_uv.reshape(-1)[:8].reshape(2, 4)  # the first four corners' memory
    shared[:] = r.quaternions
    r.quaternions = shared
    core.corner_quaternion_uv(corner_uv, 1, corner_verts, r, write_all=True)
    np.testing.assert_array_equal(corner_uv, expected)


# -------------------------------------------------------------------------------------------------
# Another Python thread writing the inputs during the call


# The cases of round 2's functions and one of the hierarchy run in the fast tier, the
# rest in the slow one: each is a child process of 300 calls.
FAST_RACES = {"bake", "bake-faces", "bake-edges", "submeshes", "across", "across-nan", "dedup", "merge", "weld",
              "corner-uv", "pairs-nan", "hierarchy-containment"}


@pytest.mark.parametrize("case", [c if c in FAST_RACES else pytest.param(c, marks=pytest.mark.slow)
                                  for c in race_child.CASES])
def test_a_thread_writing_the_inputs_during_the_call_never_crashes(case):
    """The child races a writer thread (bad indices, NaN or a negative size into the input, then
    the valid values back) against the call, 300 times: every call returns the untouched arrays'
    result (or, where the function checks nothing in that array, one of its shapes) or raises
    ValueError, and the process never dies by a signal."""
    calls = 300
    env = dict(os.environ, PYTHONPATH=str(PACKAGE_PARENT))
    r = subprocess.run([sys.executable, str(HERE / "hostile" / "race_child.py"), case, str(calls)], env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.returncode, r.stdout, r.stderr[-2000:])
    name, results, errors = r.stdout.split()
    assert name == case and int(results) + int(errors) == calls


def test_every_public_function_of_the_numpy_api_has_a_race_case():
    """Enumerated, so that a new function cannot escape the race test: every public function of
    boxmarch.core, core_boxes, core_render and core_tools is called by a case of race_child.py, or
    takes no array at all."""
    public = {name for module in (core, core_boxes, core_render, core_tools) for name, f in vars(module).items()
              if inspect.isfunction(f) and not name.startswith("_") and f.__module__ == module.__name__}
    assert len(public) > 30
    for name in race_child.TAKES_NO_ARRAY:
        assert set(inspect.signature(getattr(core, name)).parameters) <= {"index"}, name  # a turn's number
    raced = set(race_child.CASES.values())
    assert raced <= public
    assert public - raced - race_child.TAKES_NO_ARRAY == set()

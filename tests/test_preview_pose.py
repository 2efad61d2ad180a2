"""The viewport preview follows a posed armature (issue 13): a 3-bone chain rigging 36 rigidly
weighted boxes, rendered offscreen by the preview (Debian's Blender 3.4 program and the bpy 5.0
module, Mesa llvmpipe), against the CPU reference raymarch of the posed boxes computed here from the
rest boxes, the bones' rest matrices and the known joint turns (40 degrees each), not from anything
the preview computes (marched to the exact surface: the preview solves the preset in closed form).
Same tolerances as tests/test_preview.py: coverage agreement >= 99 %, 99.9th
percentile of the window depth difference <= 2e-6."""
from pathlib import Path

import numpy as np
import pytest

from boxmarch import core
from tests.helpers.preview_render import BLENDERS, EXACT_MARCH, agreement, quaternions_of, run_check_script

SCRIPT = Path(__file__).parent / "blender_scripts" / "preview_pose_check.py"

pytestmark = pytest.mark.slow  # each Blender renders the rig in a subprocess (15-30 s)


@pytest.fixture(scope="module", params=BLENDERS)
def rendered(request, package_parent, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("preview_pose")
    return run_check_script(request.param, SCRIPT, package_parent, tmp / "pose.npz", tmp)


def turn(axis, angle):
    """4 x 4 rotation about a unit axis through the origin (Rodrigues)."""
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k
    return m


def bone_motions(r, pose):
    """Each bone's motion in the mesh's object space: forward kinematics of the chain (each bone
    turned about its bone-local axis at its head, carrying its children), in the armature's space,
    then seen from the mesh (mesh_to_rig: mesh coordinates to armature coordinates)."""
    motion, out = np.eye(4), []
    for rest, axis in zip(r["bone_rest"], pose):
        motion = motion @ rest @ turn(axis, float(r["angle"])) @ np.linalg.inv(rest)
        out.append(np.linalg.inv(r["mesh_to_rig"]) @ motion @ r["mesh_to_rig"])
    return np.array(out)


def reference(r, pose=None, still_bones=()):
    """CPU reference render of the boxes, rest or moved rigidly by their bones in ``pose``."""
    centres, rotations = (r["centres"], r["rotations"]) if pose is None else posed_boxes(r, pose, still_bones)
    height, width = r["POSE_A_NORMAL_FRAME_depth"].shape
    model, view, projection = r["matrix_world"], r["view"], r["projection"]
    return core.render_boxes(centres, quaternions_of(rotations), r["sizes"] / 2, projection @ view @ model,
                             view @ model, width, height, sdf="ROUNDED_BOX", **EXACT_MARCH)


def matches(depth, ref):
    coverage, depth_error = agreement(depth, ref)
    return coverage >= 0.99 and depth_error <= 2e-6, (coverage, depth_error)


def test_bone_rest_matrices_run_along_the_bones(rendered):
    """The scene is what the reference assumes: bone y axes up the mesh's z, heads 2 apart."""
    to_mesh = np.linalg.inv(rendered["mesh_to_rig"])
    for k, rest in enumerate(rendered["bone_rest"]):
        in_mesh = to_mesh @ rest
        assert np.allclose(in_mesh[:3, 1], [0.0, 0.0, 1.0], atol=1e-6)
        assert np.allclose(in_mesh[:3, 3], [0.0, 0.0, 2.0 * k], atol=1e-5)


def test_rest_pose_matches_reference(rendered):
    ref = reference(rendered)
    assert (ref.depth < 1.0).mean() > 0.05
    ok, figures = matches(rendered["REST_NORMAL_FRAME_depth"], ref)
    assert ok, figures


@pytest.mark.parametrize("layout", ["NORMAL_FRAME", "NORMAL_COLOR"])
def test_posed_preview_matches_posed_boxes(rendered, layout):
    posed = reference(rendered, rendered["pose_a"])
    ok, figures = matches(rendered[f"POSE_A_{layout}_depth"], posed)
    assert ok, figures
    rest_coverage, _ = agreement(reference(rendered).depth, posed)
    assert rest_coverage < 0.9  # the pose moves the boxes far: a preview left at rest would fail


@pytest.mark.parametrize("layout", ["CLASSIC", "UV_FRAME"])
def test_frame_in_uvs_stays_in_rest_pose(rendered, layout):
    """Negative control: these layouts keep the frame in UV maps, which skinning does not move, so
    the positions follow the bones but the frames stay at rest, as in an engine: the check fails."""
    ok, figures = matches(rendered[f"POSE_A_{layout}_depth"], reference(rendered, rendered["pose_a"]))
    assert not ok, figures
    assert figures[1] > 1e-4


def posed_boxes(r, pose, still_bones=()):
    """(centres, rotations) of the boxes moved rigidly by their bones in ``pose`` (boxes of
    ``still_bones`` left at rest)."""
    motions = bone_motions(r, pose)
    motions[list(still_bones)] = np.eye(4)
    motions = motions[r["bone_of_box"]]
    return (np.einsum("nij,nj->ni", motions[:, :3, :3], r["centres"]) + motions[:, :3, 3],
            motions[:, :3, :3] @ r["rotations"])


def test_skinned_frames_decode_the_posed_origins(rendered):
    """Every vertex's position plus its skinned frame applied to f lands on its posed box's centre
    within 1e-5 of the box's half-extent (the preview's posed data, evaluated in Blender)."""
    centres, _ = posed_boxes(rendered, rendered["pose_a"])
    decoded = rendered["POSE_A_decoded_origins"].reshape(-1, 8, 3)
    error = np.linalg.norm(decoded - centres[:, None, :], axis=2) / (rendered["sizes"].max(axis=1)[:, None] / 2)
    assert error.max() <= 1e-5, error.max()
    assert str(rendered["VECTORS_skipped"]) == ""


def test_pose_change_keeps_what_the_pose_does_not_change(rendered):
    assert rendered["mesh_entry_kept"]  # the baked mesh's channels and GPU buffers
    assert rendered["weights_kept"]


def test_scrubbing_an_action_follows_it(rendered):
    ok, figures = matches(rendered["ACTION_1_NORMAL_FRAME_depth"], reference(rendered, rendered["pose_a"]))
    assert ok, figures
    pose_b = reference(rendered, rendered["pose_b"])
    ok, figures = matches(rendered["ACTION_11_NORMAL_FRAME_depth"], pose_b)
    assert ok, figures
    assert not matches(rendered["ACTION_1_NORMAL_FRAME_depth"], pose_b)[0]  # the two poses differ


def test_renamed_bone_is_followed(rendered):
    assert str(rendered["RENAMED_skipped"]) == ""
    ok, figures = matches(rendered["RENAMED_NORMAL_FRAME_depth"], reference(rendered, rendered["pose_b"]))
    assert ok, figures


def test_bone_that_stops_deforming_leaves_its_boxes_at_rest(rendered):
    depth = rendered["BONE2_OFF_NORMAL_FRAME_depth"]
    ok, figures = matches(depth, reference(rendered, rendered["pose_b"], still_bones=(2,)))
    assert ok, figures
    assert not matches(depth, reference(rendered, rendered["pose_b"]))[0]


def test_unfollowable_modifier_is_reported_and_skipped(rendered):
    assert "Bone Envelopes" in str(rendered["envelopes_error"])
    assert "Bone Envelopes" in str(rendered["ENVELOPES_skipped"])
    assert (rendered["ENVELOPES_NORMAL_FRAME_depth"] == 1.0).all()

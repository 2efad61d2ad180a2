"""The preview's hidden-box pre-pass (preview/occlusion.py) on a dense pile of links, in Debian's
Blender 3.4 program and the bpy 5.0 module (Mesa llvmpipe here): the picture is the one without
the pre-pass pixel for pixel and matches the CPU reference (core.render_boxes, from the links'
known centres and rotations), and the SDF evaluations counted in the shader fall as the CPU
reference's cost model counts them (its own pre-pass, computed from the same ground truth)."""
from pathlib import Path

import numpy as np
import pytest

from boxmarch import core
from tests.helpers.preview_render import BLENDERS, EXACT_MARCH, agreement, quaternions_of, run_check_script

SCRIPT = Path(__file__).parent / "blender_scripts" / "preview_occluder_check.py"

pytestmark = pytest.mark.slow  # each Blender renders the pile in a subprocess


@pytest.fixture(scope="module", params=BLENDERS)
def rendered(request, package_parent, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("occluders")
    return run_check_script(request.param, SCRIPT, package_parent, tmp / "occluders.npz", tmp)


def reference(r, occluders, **options):
    height, width = r["ON_depth"].shape
    model, view, projection = r["matrix_world"], r["view"], r["projection"]
    half = np.tile(r["link"] / 2, (len(r["centres"]), 1))
    # the bake's sort_axes_by_extent puts local x along the link's length, as the boxes are built
    return core.render_boxes(r["centres"], quaternions_of(r["rotations"]), half, projection @ view @ model,
                             view @ model, width, height, sdf="LINK", occluders=occluders, **options)


def evaluations_per_covered_pixel(steps, depth):
    covered = depth < 1.0
    return steps[..., 1][covered].sum() / covered.sum()


def test_pre_pass_changes_no_pixel(rendered):
    assert (rendered["ON_depth"] < 1.0).mean() > 0.3  # the pile fills the view
    assert np.array_equal(rendered["ON_rgba"], rendered["OFF_rgba"])
    assert np.array_equal(rendered["ON_depth"], rendered["OFF_depth"])


def test_pre_pass_picture_matches_cpu_reference(rendered):
    ref = reference(rendered, occluders=False, **EXACT_MARCH)
    coverage, depth_p999 = agreement(rendered["ON_depth"], ref)
    assert coverage >= 0.99 and depth_p999 <= 2e-6


def test_pre_pass_cuts_evaluations_as_the_cost_model_counts(rendered):
    on = evaluations_per_covered_pixel(rendered["ON_steps"], rendered["ON_depth"])
    off = evaluations_per_covered_pixel(rendered["OFF_steps"], rendered["OFF_depth"])
    model_on, model_off = (reference(rendered, occluders).cost for occluders in (True, False))
    # the link is solved in closed form, one evaluation a fragment that gets past the pre-pass (the
    # model's marched fragments); negative control: without the pre-pass the shader counts every
    # fragment
    assert rendered["OFF_steps"][..., 1].sum() == pytest.approx(model_off["marched_fragments"], rel=0.05)
    assert rendered["ON_steps"][..., 1].sum() == pytest.approx(model_on["marched_fragments"], rel=0.05)
    assert on <= 4 and off >= 2 * on, (on, off)


def test_no_pre_pass_where_the_boxes_lie_shallower_than_min_layers(rendered):
    """Below occlusion.MIN_LAYERS (forced here: no depth reaches it) the preview draws no pre-pass:
    the evaluations are those without it, to the count, and differ from those with it."""
    below, off, on = (rendered[f"{name}_steps"][..., 1] for name in ("BELOW_MIN_LAYERS", "OFF", "ON"))
    assert np.array_equal(below, off)
    assert below.sum() > on.sum()


def resolved_or_absent(rendered):
    """The resolved passes' arrays, or None in a Blender without them (3.4: no shader images),
    which must then be that version."""
    if not rendered["resolved_available"]:
        assert "RESOLVED_rgba" not in rendered
        return None
    return rendered


def test_resolved_passes_change_no_pixel(rendered):
    """preview/resolve.py (Blender 4.2 and later) draws the one-pass picture exactly, colour and
    depth; the negative control (the shade pass run with the visibility pass's word) does not."""
    r = resolved_or_absent(rendered)
    if r is None:
        return
    assert np.array_equal(r["RESOLVED_rgba"], r["OFF_rgba"])
    assert np.array_equal(r["RESOLVED_depth"], r["OFF_depth"])
    assert not np.array_equal(r["BROKEN_rgba"], r["OFF_rgba"])


def test_eye_in_a_box_of_a_mirrored_pile(rendered):
    """The eye inside a link's box of the pile mirrored in x: the boxes the near plane cuts draw no
    occluders (their shapes may not be drawn where their occluders lie), the boxes holding the eye
    march from it, the others draw with their mirrored back faces culled; with the pre-pass, in
    one pass and (Blender 4.2+) in the resolved passes, the picture is the one without it."""
    r = rendered
    assert (r["INSIDE_OFF_depth"] < 1.0).mean() > 0.9  # seen from inside the pile
    assert np.array_equal(r["INSIDE_ONE_PASS_rgba"], r["INSIDE_OFF_rgba"])
    assert np.array_equal(r["INSIDE_ONE_PASS_depth"], r["INSIDE_OFF_depth"])
    if resolved_or_absent(r) is not None:
        assert np.array_equal(r["INSIDE_RESOLVED_rgba"], r["INSIDE_OFF_rgba"])
        assert np.array_equal(r["INSIDE_RESOLVED_depth"], r["INSIDE_OFF_depth"])


def test_a_backend_that_cannot_build_the_resolved_passes_marches_in_one_pass(rendered):
    """A full-screen stage that does not compile (as on a GPU backend that refuses it): the reason
    is kept, and the picture is the one-pass march's (the eye in the mirrored pile, as above)."""
    r = resolved_or_absent(rendered)
    if r is None:
        return
    assert "compile" in str(r["fallback_refused"])
    assert np.array_equal(r["FALLBACK_rgba"], r["INSIDE_OFF_rgba"])
    assert np.array_equal(r["FALLBACK_depth"], r["INSIDE_OFF_depth"])


def test_resolved_passes_run_fewer_evaluations(rendered):
    """Counted in the shader over the fragments the passes run (the depth test culls before the
    fragment stage there): far under the every-fragment count."""
    r = resolved_or_absent(rendered)
    if r is None:
        return
    resolved = evaluations_per_covered_pixel(r["RESOLVED_steps"], r["OFF_depth"])
    one_pass = evaluations_per_covered_pixel(r["ON_steps"], r["OFF_depth"])
    off = evaluations_per_covered_pixel(r["OFF_steps"], r["OFF_depth"])
    # every covered pixel's winner solves its closed form at least once; a solve costs the same in
    # either pass, so the two passes together count about what the in-shader cut counts (where a
    # march stopped at the nearest hit kept so far, they counted less)
    assert 1.0 <= resolved <= 1.01 * one_pass, (resolved, one_pass)
    assert off >= 2 * resolved, (off, resolved)


def test_resolved_passes_run_fewer_fragments(rendered):
    """Fragments run (the STEPS output's blue: one per fragment the fragment stage ran): the one-pass
    march runs every fragment of every box, the resolved passes only those in front of the
    occluders (visibility) and of the nearest hit (shade)."""
    r = resolved_or_absent(rendered)
    if r is None:
        return
    one_pass, resolved = r["ON_steps"][..., 2].sum(), r["RESOLVED_steps"][..., 2].sum()
    covered = (r["OFF_depth"] < 1.0).sum()
    assert one_pass >= 3 * covered  # the pile: several layers of boxes over each covered pixel
    assert resolved <= one_pass / 2


def test_eye_in_a_large_box_of_a_mirrored_object(rendered):
    """The eye inside a room's box (a torus, the object mirrored): the box's far faces, which a
    mirrored object's winding makes front-facing on screen, march from the eye; the picture without
    the cut covers what the CPU reference covers, from the boxes' known centres and rotations
    (before the fix the room drew 2.7 % of the view against 23 %), and by default (culling, the
    room drawn again with both sides, the pre-pass of the small tori) it is the same picture."""
    r = rendered
    model, view, projection = r["room_matrix_world"], r["room_view"], r["room_projection"]
    height, width = r["ROOM_PLAIN_depth"].shape
    ref = core.render_boxes(r["room_centres"], quaternions_of(r["room_rotations"]), r["room_half"],
                            projection @ view @ model, view @ model, width, height, sdf="TORUS", **EXACT_MARCH)
    assert 0.1 < (ref.depth < 1.0).mean() < 0.5  # the room's far wall under an empty sky
    coverage, depth_p999 = agreement(r["ROOM_PLAIN_depth"], ref)
    assert coverage >= 0.995 and depth_p999 <= 2e-6
    assert np.array_equal(r["ROOM_DEFAULT_rgba"], r["ROOM_PLAIN_rgba"])
    assert np.array_equal(r["ROOM_DEFAULT_depth"], r["ROOM_PLAIN_depth"])


@pytest.mark.parametrize("quality", (0.5, 0.25))
def test_closed_form_keeps_its_pre_pass_below_full_quality(rendered, quality):
    """The link's closed form takes no one-tap, so occlusion.occluder_count keeps its pre-pass
    below full quality: with occlusion.MIN_LAYERS at 0 the pile seen from far draws it at 0.5 and
    0.25 as at 1.0, and its picture is the one without it (occlusion off draws none)."""
    on, off = (rendered[f"Q{quality}_{name}_rgba"] for name in ("ON", "OFF"))
    covered = off[..., 3] > 0
    assert covered.sum() > 20
    assert np.array_equal(on, off)
    assert int(rendered[f"Q{quality}_ON_pre_passes"]) > 0
    assert int(rendered["Q1.0_ON_pre_passes"]) > 0 and int(rendered[f"Q{quality}_OFF_pre_passes"]) == 0


@pytest.mark.parametrize("quality", (0.5, 0.25))
def test_no_pre_pass_below_full_quality_for_a_marched_shape(rendered, quality):
    """occlusion.occluder_count draws no pre-pass below full quality for the marched shape
    (PER_BOX_BLEND: the knob's one-tap boxes stand at their centre's depth, which may lie behind
    their own occluders); at full quality the same shape draws it (the control)."""
    assert int(rendered[f"Q{quality}_PER_BOX_BLEND_count"]) == 0
    assert int(rendered["Q1.0_PER_BOX_BLEND_count"]) > 0


def test_marches_from_the_eye_are_bounded_by_the_occluders_never_dropped(rendered):
    """The room's far faces, seen through a cluster of small tori whose occluders lie in front of
    them: a fragment that marches from the eye is not thrown away behind the occluders (its box's
    entry is the eye, in front of them), only its march is bounded. The SDF evaluations of every
    fragment with the pre-pass (STEPS, green: one a closed-form solve) are the fragments the CPU
    reference's cost model marches by that rule (core.render_boxes, occluders=True)."""
    r = rendered
    model, view, projection = r["room_matrix_world"], r["room_low_view"], r["room_low_projection"]
    height, width = r["ROOM_LOW_steps"].shape[:2]
    ref = core.render_boxes(r["room_centres"], quaternions_of(r["room_rotations"]), r["room_half"],
                            projection @ view @ model, view @ model, width, height, sdf="TORUS", occluders=True)
    assert (ref.depth < 1.0).mean() > 0.9
    assert r["ROOM_LOW_steps"][..., 1].sum() == pytest.approx(ref.cost["marched_fragments"], rel=0.05)

"""Regressions of the preview's hidden-box cut (issue 36), in Debian's Blender 3.4 program and the
bpy 5.0 module (Mesa llvmpipe here): on piles of 300 randomly rotated boxes the picture with the
pre-pass, in one pass and in the resolved passes (Blender 4.2 and later), is the one without it,
colour and depth, and the plain pile covers what the CPU reference covers.

Each scene failed before its fix (pixels changed at 200 x 150, bpy 5.0, one pass / resolved):
* vertices 100 units from the object's origin: 116 / 389; 1,000 units: 5,928 / 6,477 (float32
  rounding: box_params.glsl bm_occluder_rounding, raymarch.glsl bm_depth_rounding, and the
  march's clip-space start from gl_FragCoord in preview.frag.glsl);
* every third box open (one face deleted): 161 / 161 (an open box's occluders drew where the box
  draws nothing: mesh_data.sealed_boxes);
* the pile seen from 40 units with a near plane of 0.01: 0 / 1,505 (the resolved passes' depth
  test compared faces with the occluders' depth without bm_occluder_limit's margin, the march's
  own test with it; the pre-pass now writes the limit itself as depth). With that margin set to 0
  this scene passes (3bba224, bpy 5.0 and Blender 3.4): both tests still compare the same limit,
  and bm_depth_rounding pushes every occluder back by at least 2^-21 x |ndc z|, nearly its
  margin's 4.8e-7 where the depth nears 1;
* the pile seen by an orthographic camera 100,000 units away whose clip range (1,000 to 199,000)
  puts it at window depth 0.5: with bm_occluder_limit's margin set to 0, 2,322 px in one pass
  (bpy 5.0 and Blender 3.4; none with the margin): there the occluders' clip z is about 0, so bm_depth_rounding
  pushes them back by almost nothing, and a box's face lies less than a float step of depth in
  front of its own occluder, so the depths' rounding alone orders the two; the margin (eight float
  steps) keeps every face.
"""
from pathlib import Path

import numpy as np
import pytest

from boxmarch import core
from tests.helpers.preview_render import BLENDERS, quaternions_of, run_check_script

SCRIPT = Path(__file__).parent / "blender_scripts" / "cut_regressions_check.py"
SCENES = ("pile", "offset_100", "offset_1000", "open", "distant", "mid_depth_ortho", "squashed")

pytestmark = pytest.mark.slow  # each Blender renders the piles in a subprocess


@pytest.fixture(scope="module", params=BLENDERS)
def rendered(request, package_parent, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cut_regressions")
    return run_check_script(request.param, SCRIPT, package_parent, tmp / "cut.npz", tmp)


@pytest.mark.parametrize("scene", SCENES)
def test_the_cut_changes_no_pixel(rendered, scene):
    r = rendered
    off_rgba, off_depth = r[f"{scene}_off_rgba"], r[f"{scene}_off_depth"]
    assert (off_depth < 1.0).mean() > 0.1  # the pile is in view
    for cut in ("one_pass", "resolved") if r["resolved_available"] else ("one_pass",):
        changed = np.any(r[f"{scene}_{cut}_rgba"] != off_rgba, axis=-1) | (r[f"{scene}_{cut}_depth"] != off_depth)
        assert changed.sum() == 0, f"{scene}, {cut}: {changed.sum()} px changed"


def test_the_plain_pile_covers_what_the_reference_covers(rendered):
    r = rendered
    height, width = r["pile_off_depth"].shape
    to_view = r["view"] @ r["matrix_world"]
    reference = core.render_boxes(r["centres"], quaternions_of(r["rotations"]),
                                  np.tile([0.15, 0.125, 0.1], (len(r["centres"]), 1)), r["projection"] @ to_view,
                                  to_view, width, height, sdf="BOX")
    assert ((r["pile_off_depth"] < 1.0) == (reference.depth < 1.0)).mean() >= 0.99

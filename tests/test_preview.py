"""The viewport preview rendered by Blender's GPU module (Debian's Blender 3.4 program and the
bpy 5.0 module, both in the background on Mesa llvmpipe here) against the CPU reference raymarcher, which renders the scene from the boxes'
known centres, sizes and rotations (not from the baked data the GPU decodes).

Tolerances: coverage masks agree on >= 99% of pixels; where both hit, the 99.9th percentile of
|window depth difference| <= 2e-6, the 99th percentile of the normal angle <= 2 degrees and of
the largest colour channel difference <= 0.02 (measured: docs/PREVIEW.md)."""
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from boxmarch import core
from boxmarch.formats import layouts
from tests.helpers.blender_program import blender_env
from tests.helpers.preview_render import BLENDERS, EXACT_MARCH, agreement, quaternions_of, run_check_script

SCRIPT = Path(__file__).parent / "blender_scripts" / "preview_check.py"
OUTLINE_COLOR = (0.05, 0.05, 0.05)  # preview/draw.py OUTLINE_COLOR (that module needs bpy)

pytestmark = pytest.mark.slow  # each Blender renders the scenes in a subprocess (15-30 s)


@pytest.fixture(scope="module", params=BLENDERS)
def rendered(request, package_parent, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("preview")
    return run_check_script(request.param, SCRIPT, package_parent, tmp / "preview.npz", tmp)


# The preview's march settings, a user's map()'s (the presets are compared with EXACT_MARCH).
PREVIEW_MARCH = {"epsilon": 1e-3, "max_steps": 64, "normal": "FORWARD"}


def reference(r, sdf, view=None, projection=None, shift=0.0, **options):
    height, width = r["BOX_SHADED_depth"].shape
    model = r["matrix_world"]
    view = r["view"] if view is None else view
    projection = r["projection"] if projection is None else projection
    return core.render_boxes(r["centres"] + shift, quaternions_of(r["rotations"]), r["sizes"] / 2,
                             projection @ view @ model, view @ model, width, height, sdf=sdf,
                             base_color=r["color"][:3], **(options or EXACT_MARCH))


def reference_from_layers(r, sdf, view=None, projection=None, size=None, quality=1.0, **options):
    """The CPU reference fed with the baked layers themselves: the presets that are not symmetric
    under axis swaps depend on the frame the bake chose."""
    height, width = r["BOX_SHADED_depth"].shape if size is None else size
    model = r["matrix_world"]
    view = r["view"] if view is None else view
    projection = r["projection"] if projection is None else projection
    positions = r["layer_positions"]
    submesh_of_vertex = np.repeat(np.arange(len(positions) // 8), 8)  # 8 vertices per box, in order
    return core.render_baked_mesh(positions, r["layer_offsets"], r["layer_corner_verts"],
                                  r["layer_corner_quaternions"], submesh_of_vertex, projection @ view @ model,
                                  view @ model, width, height, sdf=sdf, base_color=r["color"][:3], quality=quality,
                                  **(options or EXACT_MARCH))


def preset_reference(r, sdf, **options):
    # presets symmetric under axis swaps: from the known boxes; the others: from the baked layers
    return reference(r, sdf, **options) if sdf in ("BOX", "SPHERE", "ROUNDED_BOX") else reference_from_layers(r, sdf, **options)


@pytest.mark.parametrize("sdf", core.SDF_PRESETS)
def test_preview_matches_cpu_reference(rendered, sdf):
    """A preset's closed-form hit against the reference marched to the exact surface: closer in
    coverage and depth than the march at the preview's settings comes (the bars: docs/PREVIEW.md)."""
    ref = preset_reference(rendered, sdf)
    depth = rendered[f"{sdf}_SHADED_depth"]
    gpu_hit, cpu_hit = depth < 1.0, ref.depth < 1.0
    assert cpu_hit.mean() > 0.1  # the scene is in view
    assert (gpu_hit == cpu_hit).mean() >= 0.999
    both = gpu_hit & cpu_hit
    assert np.percentile(np.abs(depth - ref.depth)[both], 99.9) <= 2e-6
    # the march at the preview's settings misses those bars (its epsilon fattens the shape; a
    # box's march hits at its face, as the closed form does)
    marched = preset_reference(rendered, sdf, **PREVIEW_MARCH).depth
    marched_both = both & (marched < 1.0)
    assert (sdf == "BOX" or ((marched < 1.0) != cpu_hit).mean() > 1e-3
            or np.percentile(np.abs(marched - ref.depth)[marched_both], 99.9) > 2e-6)
    normals = rendered[f"{sdf}_NORMAL_rgba"][..., :3] * 2.0 - 1.0
    angle = np.degrees(np.arccos(np.clip((normals * ref.normals).sum(-1)[both], -1.0, 1.0)))
    assert np.percentile(angle, 99) <= 2.0
    colour = np.abs(rendered[f"{sdf}_SHADED_rgba"][..., :3] - ref.rgba[..., :3])[both].max(-1)
    assert np.percentile(colour, 99) <= 0.02


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_per_box_shape_matches_cpu_reference(rendered, layout):
    """Each box draws the preset its painted shape id picks, read from the layout's channels or
    box table; the CPU reference draws the same boxes by id; with the ids shuffled it must not
    match (the negative control)."""
    height, width = rendered["BOX_SHADED_depth"].shape
    model, view, projection = rendered["matrix_world"], rendered["view"], rendered["projection"]
    positions = rendered["layer_positions"]
    n = len(positions)
    q = core.vertex_values_from_corners(rendered["layer_corner_quaternions"], rendered["layer_corner_verts"], n)
    boxes = core.boxes_from_bake(positions, rendered["layer_offsets"], q, np.repeat(np.arange(n // 8), 8))
    shapes = rendered["shapes"]
    assert set(shapes.tolist()) == set(range(len(core.SDF_PRESETS)))  # every preset is drawn

    def by_shape(ids):
        return core.render_boxes_by_shape(*boxes, ids, projection @ view @ model, view @ model, width, height, **EXACT_MARCH)
    ref = by_shape(shapes)
    assert (ref.depth < 1.0).mean() > 0.1
    coverage, depth = agreement(rendered[f"PER_BOX_{layout}_depth"], ref)
    assert coverage >= 0.99 and depth <= 2e-6, (coverage, depth)
    coverage, depth = agreement(rendered[f"PER_BOX_{layout}_depth"], by_shape(np.roll(shapes, 1)))
    assert coverage < 0.99 or depth > 1e-3, (coverage, depth)


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_every_layout_matches_cpu_reference(rendered, layout):
    """The preview drawn from each engine layout's channels (issue 12) lands on the known boxes;
    with the frame channels replaced by the identity frame it must not."""
    ref = reference(rendered, "ROUNDED_BOX")
    assert (ref.depth < 1.0).mean() > 0.1
    coverage, depth = agreement(rendered[f"LAYOUT_{layout}_depth"], ref)
    assert coverage >= 0.99 and depth <= 2e-6, (coverage, depth)
    coverage, depth = agreement(rendered[f"UNTURNED_{layout}_depth"], ref)
    assert coverage < 0.99 and depth > 1e-3, (coverage, depth)


def test_sphere_is_inside_box_and_differs_from_it(rendered):
    box, sphere = rendered["BOX_SHADED_depth"] < 1.0, rendered["SPHERE_SHADED_depth"] < 1.0
    assert not np.any(sphere & ~box)  # the largest inner sphere never leaves its box
    assert sphere.sum() < 0.8 * box.sum()


def test_user_sdf_text_block_marches(rendered):
    """The SPHERE preset written by hand as a user's map() is marched, not solved in closed form:
    it is the CPU reference's march at the preview's settings, and not the preset's picture."""
    assert rendered["user_error"] == "None"
    coverage, depth = agreement(rendered["USER_SHADED_depth"], reference(rendered, "SPHERE", **PREVIEW_MARCH))
    assert coverage >= 0.99 and depth <= 2e-6, (coverage, depth)
    coverage, depth = agreement(rendered["USER_SHADED_depth"], reference(rendered, "SPHERE"))
    assert depth > 1e-5, (coverage, depth)


def test_user_sdf_error_names_line_and_falls_back_to_outline(rendered):
    error = str(rendered["broken_error"])
    assert "broken.glsl" in error and "line 4" in error and "lenght" in error
    drawn = rendered["BROKEN_depth"] < 1.0
    assert 0 < drawn.mean() < 0.5 * (rendered["BOX_SHADED_depth"] < 1.0).mean()
    assert np.allclose(rendered["BROKEN_rgba"][drawn][:, :3], OUTLINE_COLOR[:3], atol=0.01)


def test_composites_with_scene_geometry_by_depth(rendered):
    plane_depth, composite = rendered["PLANE_depth"], rendered["COMPOSITE_depth"]
    spheres = reference(rendered, "SPHERE")
    expected = np.minimum(plane_depth, spheres.depth)
    assert (np.abs(composite - expected) <= 2e-6).mean() >= 0.99
    in_front = spheres.depth < plane_depth - 1e-4
    behind = (spheres.depth < 1.0) & (spheres.depth > plane_depth + 1e-4)
    assert in_front.sum() > 100 and behind.sum() > 100  # the plane really cuts through the spheres


def test_orthographic_camera(rendered):
    ref = reference(rendered, "SPHERE", rendered["ortho_view"], rendered["ortho_projection"])
    assert (ref.depth < 1.0).mean() > 0.05
    coverage, depth = agreement(rendered["ORTHO_depth"], ref)
    assert coverage >= 0.99 and depth <= 2e-6


def test_edited_geometry_is_drawn_after_rebake(rendered):
    moved = reference(rendered, "SPHERE", shift=rendered["shift"])
    coverage, depth = agreement(rendered["MOVED_depth"], moved)
    assert coverage >= 0.99 and depth <= 2e-6
    assert ((rendered["MOVED_depth"] < 1.0) != (rendered["SPHERE_SHADED_depth"] < 1.0)).mean() > 0.02


def test_object_frame_change(rendered):
    plain, framed, turned = (rendered[f"{k}_depth"] for k in ("TORUS", "TORUS_FRAMED", "TORUS_TURNED"))
    assert ((plain < 1.0) == (framed < 1.0)).mean() >= 0.99
    both = (plain < 1.0) & (framed < 1.0)
    assert np.percentile(np.abs(plain - framed)[both], 99.9) <= 2e-6
    assert ((plain < 1.0) != (turned < 1.0)).mean() > 0.01  # without the frame the tori turn


def view_distance(depth, projection):
    """Distance along the view axis of window depths (perspective projection)."""
    ndc = 2.0 * depth.astype(np.float64) - 1.0
    return projection[2, 3] / (ndc + projection[2, 2])


def test_quality_knob_matches_cpu_reference(rendered):
    """The preview's quality knob (secant steps, step limit, one tap) is the CPU reference's:
    TORUS at quality 0.05 on 40 x 30 px; the full-quality reference must differ more."""
    depth = rendered["QUALITY_depth"]
    low = reference_from_layers(rendered, "TORUS", rendered["quality_view"], rendered["quality_projection"],
                                size=depth.shape, quality=0.05, **PREVIEW_MARCH)
    assert low.cost["lod_fragments"] > 0 and (low.depth < 1.0).mean() > 0.1
    coverage, depth_error = agreement(depth, low)
    assert coverage >= 0.99 and depth_error <= 2e-6, (coverage, depth_error)
    full = reference_from_layers(rendered, "TORUS", rendered["quality_view"], rendered["quality_projection"],
                                 size=depth.shape, **PREVIEW_MARCH)
    full_coverage, full_depth = agreement(depth, full)
    assert full_coverage < coverage or full_depth > 1e-4, (full_coverage, full_depth)


def test_camera_inside_a_box(rendered):
    projection = rendered["inside_projection"]
    ref = reference(rendered, "SPHERE", rendered["inside_view"], projection)
    gpu_depth = rendered["INSIDE_depth"]
    assert (ref.depth < 1.0).mean() > 0.5  # only far-side fragments: without them nothing is drawn
    assert ((gpu_depth < 1.0) == (ref.depth < 1.0)).mean() >= 0.99
    both = (gpu_depth < 1.0) & (ref.depth < 1.0)
    # the GPU marches from the eye, the reference from the near plane: equal within epsilon
    error = np.abs(view_distance(gpu_depth, projection) - view_distance(ref.depth, projection))[both]
    assert np.percentile(error, 99.9) <= 2e-3


@pytest.mark.blender_program
def test_draw_handler_in_a_real_viewport(package_parent, tmp_path):  # noqa: F811
    """Blender 3.4's window under Xvfb: the POST_VIEW handler draws the raymarched shapes."""
    if shutil.which("xvfb-run") is None:
        pytest.fail("xvfb-run is missing: run scripts/setup.sh")
    out, shot = tmp_path / "viewport.json", tmp_path / "viewport.png"
    proc = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", shutil.which("blender"),
                           "--factory-startup", "--python", str(SCRIPT.parent / "viewport_check.py"), "--",
                           str(package_parent), str(out), str(shot)],
                          env=blender_env(tmp_path), capture_output=True, text=True, timeout=240)
    assert out.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads(out.read_text())
    assert result["error"] is None, result["error"]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]  # the draw handler raised nothing
    assert result["errors"] == {}
    assert result["display_type"] == "WIRE"
    assert result["red_pixels"]["False"] == 0
    assert result["red_pixels"]["True"] > 2000


def chain_contacts_px(r):
    """Pixel positions (x right, y down) of the chain's two contact points, and the pixel length
    of 0.6 object units there (the neck of radius-0.3 spheres-blend stays well inside it)."""
    height, width = r["CHAIN_PER_BOX_depth"].shape
    to_clip = r["chain_projection"] @ r["chain_view"] @ r["chain_matrix"]
    contacts = np.array([[0.5, 0.0, 0.0, 1.0], [1.5, 0.0, 0.0, 1.0], [0.5, 0.0, 0.6, 1.0]])
    clip = contacts @ to_clip.T
    ndc = clip[:, :2] / clip[:, 3:]
    px = np.stack([(ndc[:, 0] + 1) * width / 2, (1 - ndc[:, 1]) * height / 2], 1)
    return px[:2], float(np.linalg.norm(px[2] - px[0]))


def test_blend_into_parent_adds_a_neck_only_at_the_joints(rendered):
    """Three spheres in touching unit boxes, each the child of the one before, blended (radius
    0.3): the blend only adds (coverage is a superset, never farther than the hit band: a grown
    box starts its march elsewhere, so at grazing rays the hit lands elsewhere inside the
    epsilon band, measured up to 2.1e-5 of window depth), it adds many pixels, and everything it
    changes by more than 1e-4 of window depth lies near the two contact points; the same boxes
    without parents change nothing (the control)."""
    # PER_BOX is solved in closed form, PER_BOX_BLEND marched: the blend is compared with the same
    # map() without parents (CHAIN_ROOTS, marched alike); that one lies within the march's hit band
    # of PER_BOX (the control: the same coverage, the median depth within 5e-5)
    roots, blend, plain = (rendered[f"CHAIN_{k}_depth"] for k in ("ROOTS", "PER_BOX_BLEND", "PER_BOX"))
    covered, blended = roots < 1.0, blend < 1.0
    assert covered.sum() > 500
    assert not (covered & ~blended).any()
    assert (blend - roots)[covered].max() <= 5e-5
    added = blended & ~covered
    changed = added | (covered & (np.abs(blend - roots) > 1e-4))
    contacts, reach = chain_contacts_px(rendered)
    ys, xs = np.nonzero(changed)
    near = np.min(np.linalg.norm(np.stack([xs + 0.5, ys + 0.5], 1)[:, None, :] - contacts[None], axis=2), axis=1)
    assert added.sum() >= 50 and near.max() <= reach, (added.sum(), near.max(), reach)
    both = covered & (plain < 1.0)
    assert (covered == (plain < 1.0)).mean() >= 0.99 and np.median(np.abs(roots - plain)[both]) <= 5e-5

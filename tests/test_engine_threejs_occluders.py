"""The hidden-box pre-pass of the shipped three.js material (useBoxmarchOccluders, set up by
loadBoxmarch) in three.js r111 (WebGL 1) and r180 (WebGL 2) on SwiftShader, on a dense pile of
links exported with the GLTF preset: the picture is the one without the pre-pass, pixel for
pixel, and covers what the CPU reference covers; the SDF evaluations of every fragment (counted
in the shader, tests/engines/threejs.py count_job) fall as the CPU reference's cost model counts
them (core.render_boxes, from the links' known centres and rotations, with and without its own
pre-pass); without the pre-pass the count is today's (the negative control)."""
import json

import numpy as np
import pytest

from boxmarch import core, scenes
from boxmarch.preview import mesh_data
from tests.conftest import empty_scene, mesh_object
from tests.engine_scene import TO_Y_UP
from tests.engines import perspective, threejs
from tests.helpers.preview_render import EXACT_MARCH, quaternions_of
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 200, 150
LINK = np.array([0.46, 0.23, 0.06])  # scripts/chain_arm.py's link: length, width, wire thickness
LINK_MAP = "return sdf_preset_link(p, box_half);"
# Blender's (0.4, -3.5, 0.6) looking at the pile's centre, in glTF's frame (x, z, -y)
CAMERA = {"position": [0.4, 0.6, 3.5], "target": [0.0, 0.0, 0.0], "fov": 40, "near": 0.1, "far": 100}


@pytest.fixture(scope="module")
def pile(bpy_module, tmp_path_factory):
    """600 links heaped at random in a 1.6-unit cube, baked (local x along each link) and exported."""
    blender = empty_scene(bpy_module)
    rng = np.random.default_rng(5)
    centres = rng.uniform(-0.8, 0.8, (600, 3))
    rotations = scenes.random_rotations(600, rng)
    mesh_object(blender, "pile", *scenes.box_arrays(centres, np.tile(LINK, (600, 1)), rotations))
    assert blender.ops.boxmarch.bake(sort_axes_by_extent=True) == {"FINISHED"}
    path = tmp_path_factory.mktemp("occluders") / "pile.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    return path.read_bytes(), path.with_suffix(".boxmarch.json").read_bytes(), centres, rotations


def loader_js(occluders):
    """The pile as loadBoxmarch draws it, with the pre-pass (its default) or without (``occluders: false``)."""
    options = {"map": LINK_MAP, "maxSteps": 64, "epsilon": 1e-3}
    if not occluders:
        options["occluders"] = False
    return ("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'pile.glb', "
            f"{json.dumps(options)}); scene.add(loaded.scene);"
            f" if (!loaded.meshes[0].userData.boxmarchOccluders !== {json.dumps(not occluders)})"
            " throw new Error('not the pre-pass asked for');")


# How many occluder draws loadBoxmarch's pre-pass makes for each preset options.occluders names
DRAWS_JS = """async function (gltf) {
  var out = {};
  for (var name of __NAMES__) {
    var loaded = await loadBoxmarch(THREE, GLTFLoader, 'pile.glb', {map: __MAP__, occluders: name});
    out[name] = loaded.meshes[0].userData.boxmarchOccluders.scene.children.length;
  }
  return out;
}""".replace("__NAMES__", json.dumps([*core.SDF_PRESETS, "PER_BOX"])).replace("__MAP__", json.dumps(LINK_MAP))


# The pile from 8 times as far: about a tenth of a layer of boxes over the view
FAR = dict(CAMERA, position=[8 * x for x in CAMERA["position"]])
DECISION_AFTER = """var prePass = null;
    scene.traverse(function (o) { if (o.userData.boxmarchOccluders) prePass = o.userData.boxmarchOccluders; });
    return {layers: prePass.layers, drawn: prePass.drawn};"""


def decision_job(camera):
    """:class:`Job` drawing the pile as loadBoxmarch does by default from ``camera``: (Shot, the
    layers of boxes its pre-pass measured over the view, whether it ran)."""
    job = threejs.render_job(loader_js(True), W, H, camera, DECISION_AFTER)
    return threejs.Job(job.js, lambda out: (job.parse(out), out["layers"], out["drawn"]))


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def counted(request, pile):
    release = request.param
    need(threejs.available(release))
    glb, sidecar, centres, rotations = pile
    # and from inside the first link's box, where the near plane cuts the boxes around the eye
    inside = dict(CAMERA, position=(TO_Y_UP @ centres[0]).tolist())
    jobs = [threejs.count_job(loader_js(occluders), W, H, camera) for camera in (CAMERA, inside, FAR)
            for occluders in (True, False)]
    decided = [decision_job(camera) for camera in (CAMERA, FAR)]
    results = threejs.run_jobs(glb, [*jobs, DRAWS_JS, *decided], threejs.shipped_material(release), release,
                               {"pile.glb": glb, "pile.boxmarch.json": sidecar})
    names = ("on", "off", "inside_on", "inside_off", "far_on", "far_off", "draws", "decided", "far_decided")
    return dict(zip(names, results)), centres, rotations


def test_pre_pass_changes_no_pixel_with_the_eye_inside_the_pile(counted):
    """A box that the near plane cuts draws no occluders (its shape may not be drawn where they
    would lie), as a box holding the eye draws none: the picture is the one without the pre-pass."""
    out, _centres, _rotations = counted
    (on, _), (off, _) = out["inside_on"], out["inside_off"]
    assert (off.pixels[..., 3] > 0).mean() > 0.9  # seen from inside the pile
    assert np.array_equal(on.pixels, off.pixels)


def model(shot, centres, rotations, occluders, **options):
    """The CPU reference in glTF's frame, through three.js's view matrix and the GL projection;
    ``options`` (EXACT_MARCH: the surface the material's closed-form link hits) else the
    material's march settings."""
    to_clip = perspective(CAMERA, W / H) @ shot.view
    return core.render_boxes(centres @ TO_Y_UP.T, quaternions_of(TO_Y_UP @ rotations), LINK / 2, to_clip, shot.view,
                             W, H, sdf="LINK", occluders=occluders, **(options or {"max_steps": 64, "epsilon": 1e-3}))


def test_pre_pass_changes_no_pixel_and_covers_what_the_reference_covers(counted):
    out, centres, rotations = counted
    (on, _), (off, _) = out["on"], out["off"]
    assert np.array_equal(on.pixels, off.pixels)
    covered = on.pixels[..., 3] > 0
    reference = model(on, centres, rotations, False, **EXACT_MARCH).depth < 1.0
    assert covered.mean() > 0.3 and (covered == reference).mean() >= 0.99


def test_pre_pass_cuts_evaluations_as_the_cost_model_counts(counted):
    out, centres, rotations = counted
    total = {name: out[name][1].sum() for name in ("on", "off")}
    shot = out["on"][0]
    model_on, model_off = (model(shot, centres, rotations, occluders).cost for occluders in (True, False))
    # the link is solved in closed form, one evaluation a fragment that gets past the pre-pass (the
    # model's marched fragments); negative control: without the pre-pass every fragment solves
    assert total["off"] == pytest.approx(model_off["marched_fragments"], rel=0.05)
    assert total["on"] == pytest.approx(model_on["marched_fragments"], rel=0.05)
    per_covered_pixel = total["on"] / (shot.pixels[..., 3] > 0).sum()
    assert per_covered_pixel <= 4 and total["off"] >= 2 * total["on"], (per_covered_pixel, total)


def test_pre_pass_draws_each_preset_s_occluder_boxes_and_no_empty_draw(counted):
    """One draw per occluder box the CPU reference gives the preset (core.occluder_boxes: those
    with an extent in the link's box), the most any preset has for the per-box shapes."""
    out, _centres, _rotations = counted
    expected = {name: int((core.occluder_boxes(name, LINK / 2)[1][0].min(axis=1) > 0.0).sum())
                for name in core.SDF_PRESETS}
    expected["PER_BOX"] = core.occluder_boxes("BOX", LINK / 2)[0].shape[1]
    assert out["draws"] == expected


def test_pre_pass_runs_where_the_boxes_lie_min_layers_deep(counted):
    """loadBoxmarch decides as the preview does (occlusion.MIN_LAYERS, mesh_data.layers_over_view):
    the layers it measures are the preview's for the links' known centres and boxes, the pre-pass
    runs on the pile seen close and not from far, where every fragment's evaluations are those
    of ``occluders: false``, to the count (and close, fewer)."""
    from boxmarch.preview import occlusion  # imports Blender's gpu module: bpy is loaded by the pile's bake

    out, centres, _rotations = counted
    for name, runs in (("decided", True), ("far_decided", False)):
        shot, layers, drawn = out[name]
        to_clip = perspective(CAMERA, W / H) @ shot.view
        expected = mesh_data.layers_over_view(centres @ TO_Y_UP.T, np.tile(LINK / 2, (len(centres), 1)), to_clip, W, H)
        assert layers == pytest.approx(expected, rel=1e-4)
        assert drawn == runs == (layers >= occlusion.MIN_LAYERS)
    assert np.array_equal(out["far_on"][1], out["far_off"][1])
    assert (out["far_on"][0].pixels[..., 3] > 0).sum() > 100
    assert out["on"][1].sum() < out["off"][1].sum()

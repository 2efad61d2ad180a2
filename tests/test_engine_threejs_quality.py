"""The quality knob of the shipped three.js material (quality < 1; shaders/glsl/raymarch.glsl
bm_quality) in three.js r111 (WebGL 1) and r180 (WebGL 2) on SwiftShader, on the dense pile of
links of tests/test_engine_threejs_occluders.py:

* the knob sizes a pixel by the height of what is drawn into: a render target's (useBoxmarchMaterial's
  onBeforeRender, as the pre-pass sizes its own), so the pile drawn into a 100 x 75 target under a
  200 x 150 canvas is the picture of a 100 x 75 canvas, pixel for pixel;
* below full quality loadBoxmarch sets up no hidden-box pre-pass for a marched map
  (boxmarchOccluderShape's gate): the knob draws a box under 4 (1 - quality) pixels with one tap
  at its centre, which may lie behind its own occluders. The link's preset written as a user's
  map (marched, its occluders named ``LINK``) draws the picture of ``occluders: false``, and the
  loaded mesh holds no pre-pass (``userData.boxmarchOccluders``), where at quality 1 the same load
  holds one (the control: the probe sees a pre-pass where there is one). The preset's own map is
  solved in closed form, which takes no one-tap: its pre-pass stays below full quality, the
  picture the one without it. The picture alone cannot show the gate here: far off, the links'
  occluders are thinner than the pre-pass's rounding margins (bm_occluder_rounding) and draw
  nothing."""
import base64
import json

import numpy as np
import pytest

from tests.engines import threejs
from tests.helpers.tools import need
from tests.test_engine_threejs_occluders import CAMERA, LINK_MAP, pile  # noqa: F401 (fixture)

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 100, 75
# the pile from 8 times as far: the links 2-3 px long, under the one-tap size of quality 0.5 and 0.25
FAR = dict(CAMERA, position=[8 * x for x in CAMERA["position"]])
QUALITIES = (0.5, 0.25)
# the link's preset as a user's own map (the material marches it), its occluders named
MARCHED_LINK_MAP = "return 1.0 * sdf_preset_link(p, box_half);"
# whether a mesh of the scene holds a pre-pass set up by loadBoxmarch
PRE_PASS_AFTER = """var held = false;
    scene.traverse(function (object) { if (object.userData.boxmarchOccluders) held = true; });
    return {prePass: held};"""


def loader_js(quality, occluders=None, after="", sdf=LINK_MAP):
    """The pile as loadBoxmarch draws it at ``quality`` with map ``sdf`` (``occluders``: that
    option, else left out)."""
    options = {"map": sdf, "quality": quality}
    if occluders is not None:
        options["occluders"] = occluders
    return ("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'pile.glb', "
            f"{json.dumps(options)}); scene.add(loaded.scene);" + after)


# the picture of the scene drawn into a W x H render target (row 0 at the top, as Shot.pixels)
TARGET_AFTER = """var target = new THREE.WebGLRenderTarget(__W__, __H__, {minFilter: THREE.NearestFilter,
      magFilter: THREE.NearestFilter});
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    var px = new Uint8Array(__W__ * __H__ * 4);
    renderer.readRenderTargetPixels(target, 0, 0, __W__, __H__, px);
    renderer.setRenderTarget(null);
    return {target: __b64(px)};""".replace("__W__", str(W)).replace("__H__", str(H))


def target_pixels(out):
    """TARGET_AFTER's picture, rows from the top (readRenderTargetPixels starts at the bottom)."""
    return np.frombuffer(base64.b64decode(out["target"]), np.uint8).reshape(H, W, 4)[::-1].copy()


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def drawn(request, pile):  # noqa: F811 (the fixture imported above)
    release = request.param
    need(threejs.available(release))
    glb, sidecar, _centres, _rotations = pile
    # a marched map: the knob sizes marches (a closed-form map takes none)
    jobs = {"canvas": threejs.render_job(loader_js(0.25, sdf=MARCHED_LINK_MAP), W, H, CAMERA),
            "target": threejs.Job(threejs.render_job(loader_js(0.25, sdf=MARCHED_LINK_MAP), 2 * W, 2 * H, CAMERA,
                                                     TARGET_AFTER).js, target_pixels)}
    for quality in (*QUALITIES, 1.0):
        default = threejs.render_job(loader_js(quality), W, H, FAR, PRE_PASS_AFTER)
        jobs[f"default {quality}"] = threejs.Job(default.js, lambda out, shot=default.parse: (shot(out), out["prePass"]))
        jobs[f"plain {quality}"] = threejs.render_job(loader_js(quality, False), W, H, FAR)
        marched = threejs.render_job(loader_js(quality, "LINK", sdf=MARCHED_LINK_MAP), W, H, FAR, PRE_PASS_AFTER)
        jobs[f"marched {quality}"] = threejs.Job(marched.js, lambda out, shot=marched.parse: (shot(out), out["prePass"]))
        jobs[f"marched plain {quality}"] = threejs.render_job(loader_js(quality, False, sdf=MARCHED_LINK_MAP), W, H, FAR)
    results = threejs.run_jobs(glb, list(jobs.values()), threejs.shipped_material(release), release,
                               {"pile.glb": glb, "pile.boxmarch.json": sidecar})
    return dict(zip(jobs, results))


def test_the_knob_sizes_pixels_by_the_render_target_drawn_into(drawn):
    canvas, target = drawn["canvas"].pixels, drawn["target"]
    assert (canvas[..., 3] > 0).mean() > 0.3
    assert np.array_equal(target, canvas)


@pytest.mark.parametrize("quality", QUALITIES)
def test_no_pre_pass_below_full_quality_for_a_marched_map(drawn, quality):
    (marched, pre_pass), plain = drawn[f"marched {quality}"], drawn[f"marched plain {quality}"].pixels
    covered = plain[..., 3] > 0
    assert covered.sum() > 20
    assert np.array_equal(marched.pixels, plain)
    assert not pre_pass
    assert drawn["marched 1.0"][1]  # control: at full quality the same load holds its pre-pass


@pytest.mark.parametrize("quality", QUALITIES)
def test_closed_form_map_keeps_its_pre_pass_below_full_quality(drawn, quality):
    (default, pre_pass), plain = drawn[f"default {quality}"], drawn[f"plain {quality}"].pixels
    assert (plain[..., 3] > 0).sum() > 20
    assert np.array_equal(default.pixels, plain)
    assert pre_pass

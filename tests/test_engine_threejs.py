"""Proof in a real engine: the GLTF preset's .glb loaded unmodified by Debian's three.js (r111
GLTFLoader) in headless Chromium. The test decodes what three.js put in its buffers with the
documented formula (docs/ENGINES.md) and checks it against the generating box geometry; then the
shipped ShaderMaterial (shaders/threejs/boxmarch.js) raymarches every box and the pixels must cover
each box's projected silhouette within 1 px. Negative controls (a channel zeroed, the frame
replaced by the identity) must fail the same checks."""
import json

import numpy as np
import pytest

from boxmarch.preview import sources
from engine_scene import (TO_Y_UP, baked_scene, box_of_vertex, decode_normal_frame, frame_and_size_errors,
                          rounded_box_mismatch, silhouettes)
from engines import coverage_mismatch, threejs

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 320, 240
WIDE = {"position": [2.0, 9.0, 14.0], "target": [0.5, -0.5, 0.0], "fov": 50, "near": 0.5, "far": 100}
# The far plane leaves only the three 0.02 x 0.02 x 0.1 boxes (numbers 3-5) in this view.
CLOSE = {"position": [0.12, 0.2, 0.3], "target": [0.0, 0.0, 0.0], "fov": 30, "near": 0.01, "far": 0.6}
IN_VIEW = {id(WIDE): slice(None), id(CLOSE): slice(3, 6)}
# A box at 0.6 of each box's half-extents about its decoded origin: unlike the full box, which
# the rasterised mesh already outlines, it lands right only if origin, axes and extents do.
BOX_MAP = "return sd_box(p, 0.6 * box_half);"
INNER = 0.6
ROUNDED_MAP = "return sd_round_box(p, box_half, 0.1 * min3(box_half));"


@pytest.fixture
def exported(blender, tmp_path):
    reason = threejs.available()
    if reason:
        pytest.skip(reason)
    ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path / "mixed.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    return path.read_bytes(), centres, sizes, rotations


def material_js():
    return (sources.shader_dir() / "threejs" / "boxmarch.js").read_text()


def setup_js(sdf_body, tamper=""):
    """Gives every mesh the shipped material; ``tamper`` (JS, with ``g`` the geometry) runs first."""
    return (f"gltf.scene.traverse(function (o) {{ if (!o.isMesh) return; var g = o.geometry; {tamper}\n"
            f"useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {{map: {json.dumps(sdf_body)}, "
            f"color: new THREE.Color(1, 1, 1), maxSteps: 256}})); }});")


def covered(shot):
    return shot.pixels[..., 3] > 0


def test_threejs_receives_every_channel_and_decodes_to_the_boxes(exported):
    glb, centres, sizes, rotations = exported
    (mesh,) = threejs.load_attributes(glb)
    a = mesh["attributes"]
    assert {"position", "normal", "tangent", "uv", "uv2", "texcoord_2", "texcoord_3", "texcoord_4"} <= set(a)
    assert not any(mesh["normalized"].values())
    box = box_of_vertex(a["position"], centres, sizes, rotations, TO_Y_UP)
    offset = np.concatenate([a["uv2"], a["texcoord_2"][:, :1]], axis=1)
    half = np.concatenate([a["texcoord_3"], a["texcoord_4"][:, :1]], axis=1)
    origins, axes, half = decode_normal_frame(a["position"], a["normal"], a["tangent"], offset, half)
    origin_error, axis_error, half_error = frame_and_size_errors(origins, axes, half, box, centres, sizes,
                                                                 rotations, TO_Y_UP)
    assert origin_error < 1e-5 and axis_error < 1e-6 and half_error < 1e-5, (origin_error, axis_error, half_error)
    index = a["texcoord_2"][:, 1]
    assert np.array_equal(index, np.rint(index))
    for b in range(len(centres)):  # one number per box, a different one for every box
        assert len(set(index[box == b])) == 1
    assert len(set(index)) == len(centres) and set(index) == set(range(len(centres)))


@pytest.mark.parametrize("camera", [WIDE, CLOSE], ids=["all-boxes", "close-up-on-0.02-boxes"])
def test_threejs_raymarches_each_box_at_its_own_size(exported, camera):
    glb, centres, sizes, rotations = exported
    shot = threejs.render(glb, material_js(), setup_js(BOX_MAP), W, H, camera)
    view = IN_VIEW[id(camera)]
    expected = silhouettes(shot, centres[view], INNER * sizes[view], rotations[view], TO_Y_UP)
    mismatch = coverage_mismatch(covered(shot), expected)
    assert mismatch is None, mismatch
    assert covered(shot).sum() > 500


def test_threejs_rounded_boxes_lie_between_the_box_and_its_core(exported):
    """Rounded boxes of radius r = 0.1 x the smallest half-extent: every covered pixel within 1 px
    of the box, every pixel of the box shrunk by r (the core) covered."""
    glb, centres, sizes, rotations = exported
    for camera in (WIDE, CLOSE):
        shot = threejs.render(glb, material_js(), setup_js(ROUNDED_MAP), W, H, camera)
        view = IN_VIEW[id(camera)]
        mismatch = rounded_box_mismatch(covered(shot), shot, centres[view], sizes[view], rotations[view], TO_Y_UP)
        assert mismatch is None, mismatch


@pytest.mark.parametrize("tamper", [
    "g.getAttribute('uv2').array.fill(0); g.getAttribute('texcoord_2').array.fill(0);",  # offset channel dropped
    "var n = g.getAttribute('normal').array, t = g.getAttribute('tangent').array;"        # frame not rotated
    "for (var i = 0; i < n.length / 3; i++) { n.set([0, 0, 1], 3 * i); t.set([1, 0, 0, 1], 4 * i); }",
], ids=["offset-zeroed", "identity-frame"])
def test_threejs_negative_controls_fail(exported, tamper):
    glb, centres, sizes, rotations = exported
    shot = threejs.render(glb, material_js(), setup_js(BOX_MAP, tamper), W, H, WIDE)
    assert coverage_mismatch(covered(shot), silhouettes(shot, centres, INNER * sizes, rotations, TO_Y_UP)) is not None


def test_material_refuses_a_classic_export(blender, tmp_path):
    if threejs.available():
        pytest.skip(threejs.available())
    baked_scene(blender)
    path = tmp_path / "classic.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF", layout="CLASSIC") == {"FINISHED"}
    with pytest.raises(RuntimeError, match="no TEXCOORD_3"):
        threejs.render(path.read_bytes(), material_js(), setup_js(BOX_MAP), 8, 8, WIDE)

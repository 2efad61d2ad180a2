"""Regressions of the hidden-box cut in the shipped three.js material (loadBoxmarch's pre-pass and
useBoxmarchVisibility's passes, issue 36), r111 (WebGL 1) and r180 (WebGL 2) on SwiftShader: on
piles of randomly rotated boxes baked and exported with the GLTF preset, the picture with the cut
is the one without it (``occluders: false``), pixel for pixel, and the plain picture covers what
the CPU reference (core.render_boxes, from the boxes' known centres and rotations) covers.

Each case fails without its fix (the first 16 fail on the material before this test; pixels the cut
emptied at 200 x 150 on r111, each measured with the other fixes in place):
* a plain pile, the default map: 791 px; ``sdf_preset_box`` with BOX occluders: 475 px (the
  rasteriser's sub-pixel snapping moved occluder faces in front of their boxes' faces at a slant:
  box_params.glsl bm_occluder_rounding);
* the pile 1,000 units from the object's origin: 4,437 px (float32 rounding of the vertices);
* every third box open (one face deleted): 91 px (box_params.glsl sealed boxes:
  boxmarchSealedTriangles);
* the pile turned inside out, ``visibilityPass: true``: 14,516 px (its passes drew front faces
  only, an inside-out box's far side);
* the pile seen from 11 times as far with a near plane of 0.01, ``visibilityPass: true``: 29 px
  (the shade pass's box test had no margin for the depth's rounding near the far plane:
  raymarch.glsl bm_shade_margin);
* the pile mirrored (scale -1 along x), ``visibilityPass: true``: 14,410 px, all it covered (the composite, a
  child of the mesh, is wound clockwise under the mirroring matrix and was culled:
  createBoxmarchScreenMaterial draws both sides).
* the pile at window depth 0.5 under an orthographic camera 100,000 units away (clip range 1,000
  to 199,000) with bm_occluder_limit's margin set to 0: 39 px (r180) and 27 px (r111) with the
  pre-pass, 1,001 px with the visibility passes, in both; none with the margin (there
  bm_depth_rounding pushes the occluders back by almost nothing: their clip z is about 0).
* the pile squashed (scale 0.3, 1.4, 1 along x, y, z), with the pre-pass and with the visibility
  passes: 6 px each, on r111 and r180 (the pre-pass sized a pixel, which its occluders are pulled in
  by an eighth of, along the object-to-clip matrix's y row alone: 3.3 times too small in object
  units across the squashed axis, so an occluder's face lay less than the rasteriser's sub-pixel
  snapping behind its box's face; a pixel across each face is now the view-space pixel times
  |normalMatrix a|: template.js BOXMARCH_OCCLUDER_VERTEX).
The mirrored pile with the default cuts (pre-pass, culling) passed before: it keeps every cut
checked on a mirroring matrix.
"""
import json

import numpy as np
import pytest

from boxmarch import core, scenes
from tests.conftest import empty_scene
from tests.engine_scene import TO_Y_UP
from tests.engines import perspective, threejs
from tests.helpers.preview_render import quaternions_of
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 200, 150
SIZE = np.array([0.3, 0.25, 0.2])
COUNT = 300
BOX_MAP = "return sdf_preset_box(p, box_half);"
# the pile's scale in "squashed" cases: thin across the view, so its boxes' faces turn edge-on
SQUASH = (0.3, 1.4, 1.0)
NEAR_CAMERA = {"position": [0.4, 0.6, 3.5], "target": [0.0, 0.0, 0.0], "fov": 40, "near": 0.1, "far": 100}


def far(camera, offset):
    """``camera`` moved with a scene ``offset`` units out along each of Blender's axes (glTF: x, z, -y)."""
    shift = TO_Y_UP @ np.full(3, offset)
    return dict(camera, position=(np.array(camera["position"]) + shift).tolist(), target=shift.tolist())


DISTANT_CAMERA = dict(NEAR_CAMERA, position=(np.array(NEAR_CAMERA["position"]) * 40 / 3.5).tolist(), fov=4,
                      near=0.01, far=1000)

# An orthographic camera 100,000 units away whose clip range puts the pile at window depth 0.5
# (the Blender preview's mid_depth_ortho, tests/test_cut_regressions.py)
MID_DEPTH_ORTHO = {"position": (np.array(NEAR_CAMERA["position"]) / np.linalg.norm(NEAR_CAMERA["position"]) * 1e5).tolist(),
                   "target": [0.0, 0.0, 0.0], "ortho": 1.0, "near": 1e3, "far": 2e5 - 1e3}


def pile_arrays(offset=0.0, opened=0, flipped=False):
    """The pile's mesh arrays: COUNT boxes of SIZE at random places (seed 1) and rotations,
    ``offset`` units out; every ``opened``-th box without its first face; ``flipped``: every face
    wound the other way."""
    rng = np.random.default_rng(1)
    centres = rng.uniform(-0.8, 0.8, (COUNT, 3)) + offset
    rotations = scenes.random_rotations(COUNT, rng)
    positions, _edges, starts, sizes, corners = scenes.box_arrays(centres, np.tile(SIZE, (COUNT, 1)), rotations)
    faces = [corners[s:s + n] for s, n in zip(starts, sizes)]
    if opened:
        faces = [face for k, face in enumerate(faces) if k % (6 * opened)]
    if flipped:
        faces = [face[::-1] for face in faces]
    sizes = np.array([len(f) for f in faces], np.int32)
    return (positions, None, np.r_[0, np.cumsum(sizes)[:-1]].astype(np.int32), sizes,
            np.concatenate(faces).astype(np.int32)), centres, rotations


@pytest.fixture(scope="module")
def exported(bpy_module, tmp_path_factory):
    """{name: (glb, sidecar)} of each pile, baked and exported with the GLTF preset; and the
    plain pile's centres and rotations."""
    from boxmarch import mesh_io

    folder = tmp_path_factory.mktemp("cut_regressions")
    files, truth = {}, None
    for name, options in {"pile": {}, "far": {"offset": 1000.0}, "open": {"opened": 3}, "flipped": {"flipped": True}}.items():
        blender = empty_scene(bpy_module)
        (positions, _edges, starts, sizes, corners), centres, rotations = pile_arrays(**options)
        ob = blender.data.objects.new(name, mesh_io.new_mesh(name, positions, starts, sizes, corners))
        blender.context.scene.collection.objects.link(ob)
        ob.select_set(True)
        blender.context.view_layer.objects.active = ob
        assert blender.ops.boxmarch.bake() == {"FINISHED"}
        path = folder / f"{name}.glb"
        assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
        files[name] = (path.read_bytes(), path.with_suffix(".boxmarch.json").read_bytes())
        truth = truth or (centres, rotations)
    return files, truth


def loader_js(name, options):
    """Loads ``name`` (a key of ``exported``; "NAME mirrored": NAME's scene scaled by -1 along x;
    "NAME squashed": scaled by SQUASH)."""
    transforms = {" mirrored": " loaded.scene.scale.x = -1;",
                  " squashed": " loaded.scene.scale.set(%s);" % ", ".join(map(str, SQUASH))}
    suffix = next((s for s in transforms if name.endswith(s)), "")
    return (f"scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, "
            f"'{name.removesuffix(suffix) if suffix else name}.glb', {json.dumps(options)}); scene.add(loaded.scene);"
            + transforms.get(suffix, ""))


# (scene, camera, options with the cut): each drawn with them and with occluders: false
CASES = {
    "default map": ("pile", NEAR_CAMERA, {}),
    "box map": ("pile", NEAR_CAMERA, {"map": BOX_MAP}),
    "per-box map": ("pile", NEAR_CAMERA, {"map": "return bm_sdf_by_id(box_params.x, p, box_half);"}),
    "vertices 1,000 units out": ("far", far(NEAR_CAMERA, 1000.0), {"map": BOX_MAP}),
    "open boxes": ("open", NEAR_CAMERA, {"map": BOX_MAP}),
    "open boxes, visibility passes": ("open", NEAR_CAMERA, {"map": BOX_MAP, "visibilityPass": True}),
    "inside out, visibility passes": ("flipped", NEAR_CAMERA, {"map": BOX_MAP, "visibilityPass": True}),
    "distant, visibility passes": ("pile", DISTANT_CAMERA, {"map": BOX_MAP, "visibilityPass": True}),
    "mirrored": ("pile mirrored", NEAR_CAMERA, {"map": BOX_MAP}),
    "mirrored, visibility passes": ("pile mirrored", NEAR_CAMERA, {"map": BOX_MAP, "visibilityPass": True}),
    "squashed": ("pile squashed", NEAR_CAMERA, {"map": BOX_MAP}),
    "squashed, visibility passes": ("pile squashed", NEAR_CAMERA, {"map": BOX_MAP, "visibilityPass": True}),
    "mid-depth orthographic": ("pile", MID_DEPTH_ORTHO, {"map": BOX_MAP}),
    "mid-depth orthographic, visibility passes": ("pile", MID_DEPTH_ORTHO, {"map": BOX_MAP, "visibilityPass": True}),
}


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def drawn(request, exported):
    release = request.param
    need(threejs.available(release))
    files, truth = exported
    jobs = []
    for scene, camera, options in CASES.values():
        jobs.append(threejs.render_job(loader_js(scene, options), W, H, camera))
        jobs.append(threejs.render_job(loader_js(scene, dict(options, occluders=False, visibilityPass=False)), W, H,
                                       camera))
    served = {f"{name}.{kind}": data for name, pair in files.items()
              for kind, data in zip(("glb", "boxmarch.json"), pair)}
    # a page of 24 pictures: more than threejs.TIMEOUT_S on a loaded 2-core machine
    shots = threejs.run_jobs(files["pile"][0], jobs, threejs.shipped_material(release), release, served, 600)
    return {case: (shots[2 * k], shots[2 * k + 1]) for k, case in enumerate(CASES)}, truth


@pytest.mark.parametrize("case", CASES)
def test_the_cut_changes_no_pixel(drawn, case):
    out, _truth = drawn
    cut, plain = out[case]
    assert (plain.pixels[..., 3] > 0).mean() > 0.2  # the pile is in view
    changed = np.abs(cut.pixels.astype(int) - plain.pixels).max(axis=-1) > 1
    assert changed.sum() == 0, f"{case}: {changed.sum()} px changed"


def test_the_plain_pile_covers_what_the_reference_covers(drawn):
    """The pictures compared are the pile's: the plain one covers what the CPU reference covers."""
    out, (centres, rotations) = drawn
    _cut, plain = out["box map"]
    to_clip = perspective(NEAR_CAMERA, W / H) @ plain.view
    reference = core.render_boxes(centres @ TO_Y_UP.T, quaternions_of(TO_Y_UP @ rotations),
                                  np.tile(SIZE / 2, (COUNT, 1)), to_clip, plain.view, W, H, sdf="BOX")
    assert ((plain.pixels[..., 3] > 0) == (reference.depth < 1.0)).mean() >= 0.99

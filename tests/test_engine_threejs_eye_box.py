"""The eye inside a large box of a mirrored object in the shipped three.js material (r111 and r180
on SwiftShader): the room of tests/blender_scripts/preview_occluder_check.py (a torus's box, the
eye in the torus's hole, 20 small tori inside the tube; the object scaled -1 in x), baked and
exported with the GLTF preset. The box holding the eye marches from the eye; the picture covers
what the CPU reference covers (core.render_boxes from the boxes' known centres and rotations, the
same march settings), without the cut (``occluders: false, cullBackFaces: false``) and by default
(where culling redraws the room with both sides: without that pass the room is missing, the
negative control)."""
import json

import numpy as np
import pytest

from boxmarch import core, scenes
from tests.conftest import empty_scene, mesh_object
from tests.engine_scene import TO_Y_UP
from tests.engines import perspective, threejs
from tests.helpers.preview_render import quaternions_of
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 160, 120
MIRROR = np.diag([-1.0, 1.0, 1.0])
EYE, LOOK = np.array([0.3, 0.2, 0.1]), np.array([1.0, 0.1, 0.6])  # object space (Blender's frame)
MARCH = {"map": "return sdf_preset_torus(p, box_half);", "maxSteps": 64, "epsilon": 1e-3}


@pytest.fixture(scope="module")
def room(bpy_module, tmp_path_factory):
    blender = empty_scene(bpy_module)
    rng = np.random.default_rng(3)
    centres = np.vstack([[0.0, 0.0, 0.0], np.c_[rng.uniform(1.9, 2.7, 20), rng.uniform(-1.2, 1.2, 20),
                                               rng.uniform(-0.4, 0.4, 20)]])
    sizes = np.vstack([[6.0, 6.0, 1.6], np.tile([0.3, 0.3, 0.1], (20, 1))])
    rotations = np.vstack([np.eye(3)[None], scenes.random_rotations(20, rng)])
    ob = mesh_object(blender, "room", *scenes.box_arrays(centres, sizes, rotations))
    assert blender.ops.boxmarch.bake(sort_axes_by_extent=False) == {"FINISHED"}
    ob.scale = (-1.0, 1.0, 1.0)
    path = tmp_path_factory.mktemp("eye_box") / "room.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    return path.read_bytes(), path.with_suffix(".boxmarch.json").read_bytes(), centres, sizes / 2, rotations


def loader_js(options, after=""):
    return ("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'room.glb', "
            f"{json.dumps(dict(MARCH, **options))}); scene.add(loaded.scene);" + after)


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def drawn(request, room):
    release = request.param
    need(threejs.available(release))
    glb, sidecar, *_ = room
    camera = {"position": (TO_Y_UP @ MIRROR @ EYE).tolist(), "target": (TO_Y_UP @ MIRROR @ (EYE + LOOK)).tolist(),
              "up": (TO_Y_UP @ [0.0, 0.0, 1.0]).tolist(), "fov": 40, "near": 0.1, "far": 100}
    no_eye_box = " loaded.meshes[0].onAfterRender = function () {};"
    jobs = [threejs.render_job(loader_js(options, after), W, H, camera)
            for options, after in (({"occluders": False, "cullBackFaces": False}, ""), ({}, ""), ({}, no_eye_box))]
    shots = threejs.run_jobs(glb, jobs, threejs.shipped_material(release), release,
                             {"room.glb": glb, "room.boxmarch.json": sidecar})
    return dict(zip(("plain", "default", "no eye box"), shots)), camera


def test_eye_in_a_large_box_of_a_mirrored_object_covers_what_the_reference_covers(drawn, room):
    shots, camera = drawn
    _glb, _sidecar, centres, half, rotations = room
    to_view = shots["plain"].view @ np.block([[TO_Y_UP @ MIRROR, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]])
    ref = core.render_boxes(centres, quaternions_of(rotations), half, perspective(camera, W / H) @ to_view, to_view,
                            W, H, sdf="TORUS", max_steps=MARCH["maxSteps"], epsilon=MARCH["epsilon"])
    covered = ref.depth < 1.0
    assert 0.1 < covered.mean() < 0.5  # the room's far wall under an empty sky
    for name in ("plain", "default"):
        assert ((shots[name].pixels[..., 3] > 0) == covered).mean() >= 0.995, name
    # negative control: without the culled mesh's second draw of the box holding the eye, its wall is missing
    assert ((shots["no eye box"].pixels[..., 3] > 0) == covered).mean() < 0.9

"""The eye inside a box that holds a second box behind the first's visible surface (issue 36, items
10 and 11): a box of half-extent 3 drawn as a sphere (the SPHERE preset: radius 3), the eye in
its corner outside the sphere, looking across the sphere's near side at a small box nested inside
the sphere (its own sphere of radius 0.35 lies wholly inside the big one, so nothing of it is
visible), and a tiny box in front of the sphere's surface (visible). The box holding the eye
marches from the eye, its fragments its far side: its hit must be written at its own depth, not
clamped to that far side, or the nested box, nearer than the far side, shows through the sphere.

The truth is computed here from the geometry (ray-sphere intersections in float64 from the eye
through each pixel centre), not by the code under test. Checked in the CPU reference
(core.render_boxes), the Blender preview (bpy module, llvmpipe: one pass, the culled default and
the resolved passes) and three.js r111 and r180 (SwiftShader: without the cut, by default and with
the visibility passes). Negative control: without the big box the nested one covers hundreds of
pixels, so a picture that showed it would fail. Before the fix each renderer showed it on
the pixels counted in docs/PREVIEW.md ("The eye inside a box")."""
import json

import numpy as np
import pytest

from boxmarch import core
from tests.conftest import empty_scene, mesh_object
from tests.engine_scene import TO_Y_UP
from tests.engines import perspective, threejs, view_matrix
from tests.helpers.preview_render import EXACT_MARCH
from tests.helpers.tools import need

W, H = 64, 48
EYE = np.array([2.6, -2.6, 0.0])  # Blender's frame: inside the big box, outside its sphere (|EYE| 3.68)
# the nested box: its centre where the ray from the eye passes 2.3 from the big sphere's centre
# (the ray enters the sphere at 0.94 from the eye, at 50 degrees to its normal; the nested sphere
# lies from 2.52 to 3.22, the big box's far side at 5.6)
NESTED = 2.3 * np.array([np.cos(np.radians(6.3)), np.sin(np.radians(6.3)), 0.0])
# the tiny box between the eye and the sphere (0.55 from the eye, 3.27 from the centre)
FRONT = EYE + 0.55 * (NESTED - EYE) / np.linalg.norm(NESTED - EYE) + np.array([0.0, 0.0, 0.12])
CENTRES = np.array([[0.0, 0.0, 0.0], NESTED, FRONT])
RADII = np.array([3.0, 0.35, 0.1])  # the SPHERE preset's radius: the least half-extent
CAMERA = {"position": EYE.tolist(), "target": NESTED.tolist(), "up": [0.0, 0.0, 1.0], "fov": 40.0, "near": 0.05,
          "far": 20.0}
SHOWN_TOLERANCE = 1e-4  # window depth: the nested box's hit against the truth's (they differ by 0.02 or more)


def truth(to_clip, eye, centres, radii, width, height):
    """(depth, surface, normal) per pixel from the geometry: the window depth (1: none), the index
    of the nearest sphere hit (-1: none) and its unit normal, of the ray from ``eye`` through each
    pixel centre of a ``to_clip`` view (float64; row 0 at the top)."""
    from_clip = np.linalg.inv(to_clip)
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    far = np.stack([xs / width * 2 - 1, 1 - ys / height * 2, np.ones_like(xs), np.ones_like(xs)], -1) @ from_clip.T
    rays = far[..., :3] / far[..., 3:] - eye
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    t = np.full((height, width), np.inf)
    surface = np.full((height, width), -1)
    for k, (centre, radius) in enumerate(zip(centres, radii)):
        o = eye - centre
        b = rays @ o
        h = b * b - (o @ o - radius * radius)
        root = -b - np.sqrt(np.maximum(h, 0.0))
        nearer = (h >= 0) & (root > 0) & (root < t)
        t[nearer], surface[nearer] = root[nearer], k
    points = eye + rays * np.where(np.isfinite(t), t, 0.0)[..., None]
    clip = np.c_[points.reshape(-1, 3), np.ones(points.size // 3)] @ to_clip.T
    with np.errstate(divide="ignore", invalid="ignore"):  # pixels of no hit: their depth is 1 below
        window = (clip[:, 2] / clip[:, 3] * 0.5 + 0.5).reshape(height, width)
    depth = np.where(surface >= 0, window, 1.0)
    normal = (points - centres[np.maximum(surface, 0)]) / radii[np.maximum(surface, 0)][..., None]
    return depth, surface, normal


def nested_shown(depth, to_clip, eye=EYE, centres=CENTRES, radii=RADII):
    """Pixels of ``depth`` (a renderer's window depth) showing the nested box's sphere where the
    truth shows another surface in front of it."""
    height, width = depth.shape
    true_depth, surface, _ = truth(to_clip, eye, centres, radii, width, height)
    alone, alone_surface, _ = truth(to_clip, eye, centres[1:2], radii[1:2], width, height)
    return (alone_surface == 0) & (surface != 1) & (np.abs(depth - alone) < SHOWN_TOLERANCE) \
        & (alone - true_depth > 10 * SHOWN_TOLERANCE)


def reference_matrices():
    view = view_matrix(CAMERA)
    return view, perspective(CAMERA, W / H) @ view


def test_the_scene_hides_the_nested_box_and_shows_the_front_one():
    """The geometry as described: the nested sphere inside the big one (never visible), in view and
    covering hundreds of pixels without the big box (the negative control's reach); the front box
    in front of the big sphere's surface and visible."""
    _view, to_clip = reference_matrices()
    assert np.linalg.norm(NESTED) + RADII[1] < RADII[0] < np.linalg.norm(EYE)
    assert np.all(np.abs(CENTRES) + RADII[:, None] <= 3.0)  # every box inside the big one
    _depth, surface, _normal = truth(to_clip, EYE, CENTRES, RADII, W, H)
    _alone, alone_surface, _ = truth(to_clip, EYE, CENTRES[1:2], RADII[1:2], W, H)
    assert (surface == 1).sum() == 0 and (alone_surface == 0).sum() > 150
    assert (surface == 2).sum() > 30 and (surface == 0).sum() > 0.5 * W * H


@pytest.mark.parametrize("occluders", (False, True))
def test_cpu_reference_hides_the_nested_box(occluders):
    view, to_clip = reference_matrices()
    half = np.repeat(RADII[:, None], 3, axis=1)
    quaternions = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))
    image = core.render_boxes(CENTRES, quaternions, half, to_clip, view, W, H, sdf="SPHERE", occluders=occluders,
                              **EXACT_MARCH)
    true_depth, surface, _ = truth(to_clip, EYE, CENTRES, RADII, W, H)
    assert nested_shown(image.depth, to_clip).sum() == 0
    assert (np.abs(image.depth - true_depth) < SHOWN_TOLERANCE).mean() >= 0.99
    # negative control: the nested box alone shows where the picture above hides it
    alone = core.render_boxes(CENTRES[1:2], quaternions[1:2], half[1:2], to_clip, view, W, H, sdf="SPHERE",
                              **EXACT_MARCH)
    shown_alone = np.abs(alone.depth - truth(to_clip, EYE, CENTRES[1:2], RADII[1:2], W, H)[0]) < SHOWN_TOLERANCE
    assert (shown_alone & (alone.depth < 1.0)).sum() > 150


@pytest.fixture(scope="module", params=("outward", "inside-out"))
def room(request, bpy_module, tmp_path_factory):
    """The scene as one object of three boxes, baked, previewed as SPHERE from the eye, and
    exported with the GLTF preset: the preview's pictures and the .glb with its sidecar. The big
    box wound outward, or inside out (every face of it wound the other way: its far side, seen
    from the eye, faces the eye, and must still march from the eye)."""
    from boxmarch import preview, scenes
    from boxmarch.preview import draw, occlusion, resolve

    blender = empty_scene(bpy_module)
    positions, edges, starts, sizes, corners = scenes.box_arrays(CENTRES, 2 * np.repeat(RADII[:, None], 3, axis=1),
                                                                 np.tile(np.eye(3), (3, 1, 1)))
    if request.param == "inside-out":  # the big box's six faces, the first ones, reversed
        corners = corners.copy()
        for start, size in zip(starts[:6], sizes[:6]):
            corners[start:start + size] = corners[start:start + size][::-1]
    ob = mesh_object(blender, "room", positions, edges, starts, sizes, corners)
    assert blender.ops.boxmarch.bake(sort_axes_by_extent=False) == {"FINISHED"}
    ob.boxmarch.preview = True
    ob.boxmarch.sdf = "SPHERE"
    scene = blender.context.scene
    camera = blender.data.objects.new("camera", blender.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    from mathutils import Vector
    camera.location = Vector(EYE)
    camera.rotation_euler = (Vector(NESTED) - Vector(EYE)).to_track_quat("-Z", "Y").to_euler()
    camera.data.clip_start, camera.data.clip_end = CAMERA["near"], CAMERA["far"]
    camera.data.sensor_fit, camera.data.angle = "VERTICAL", np.radians(CAMERA["fov"])
    scene.camera = camera
    blender.context.view_layer.update()
    view, projection = preview.camera_matrices(scene, camera, W, H)
    pictures = {"to_clip": projection @ view @ np.array(ob.matrix_world)}
    switches = draw.CULL_BACK_FACES, occlusion.ENABLED, resolve.ENABLED, occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW
    try:
        occlusion.MIN_LAYERS = resolve.MIN_OVERDRAW = 0.0  # every cut whatever the depth of the boxes
        configs = {"plain": (False, False, False), "default": (True, True, False), "resolved": (True, True, True)}
        for name, (cull, enabled, resolved) in configs.items():
            draw.CULL_BACK_FACES, occlusion.ENABLED, resolve.ENABLED = cull, enabled, resolved
            pictures[name] = preview.render(scene, camera, W, H)[1]
        pictures["resolved_available"] = resolve.available()
    finally:
        draw.CULL_BACK_FACES, occlusion.ENABLED, resolve.ENABLED, occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = switches
    path = tmp_path_factory.mktemp("eye_box_depth") / "room.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    return pictures, path.read_bytes(), path.with_suffix(".boxmarch.json").read_bytes()


@pytest.mark.slow
@pytest.mark.parametrize("config", ("plain", "default", "resolved"))
def test_preview_hides_the_nested_box(room, config):
    pictures = room[0]
    # the resolved passes need shader images (Blender 4.2 and later: every bpy this tier runs)
    assert config != "resolved" or pictures["resolved_available"], "this Blender has no resolved passes"
    depth, to_clip = pictures[config], pictures["to_clip"]
    true_depth = truth(to_clip, EYE, CENTRES, RADII, W, H)[0]
    assert nested_shown(depth, to_clip).sum() == 0, config
    assert (np.abs(depth - true_depth) < SHOWN_TOLERANCE).mean() >= 0.99, config


def grey(shot, to_view, to_clip):
    """The grey level three.js's material shades each pixel's true surface with
    (bmColor 0.8 x (0.35 + 0.65 max(n_view.z, 0))), 0 where none; and the same for the nested
    sphere alone."""
    levels = []
    for centres, radii in ((CENTRES, RADII), (CENTRES[1:2], RADII[1:2])):
        _depth, surface, normal = truth(to_clip, EYE, centres, radii, W, H)
        n_view = normal @ to_view[:3, :3].T
        levels.append(np.where(surface >= 0, 255 * 0.8 * (0.35 + 0.65 * np.maximum(n_view[..., 2], 0.0)), 0.0))
    return levels


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def drawn(request, room):
    release = request.param
    need(threejs.available(release))
    _pictures, glb, sidecar = room
    camera = dict(CAMERA, position=(TO_Y_UP @ EYE).tolist(), target=(TO_Y_UP @ NESTED).tolist(),
                  up=(TO_Y_UP @ [0.0, 0.0, 1.0]).tolist())
    march = {"map": "return sdf_preset_sphere(p, box_half);"}
    jobs = [threejs.render_job("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, "
                               f"'room.glb', {json.dumps(dict(march, **options))}); scene.add(loaded.scene);",
                               W, H, camera)
            for options in ({"occluders": False, "cullBackFaces": False}, {}, {"visibilityPass": True})]
    shots = threejs.run_jobs(glb, jobs, threejs.shipped_material(release), release,
                             {"room.glb": glb, "room.boxmarch.json": sidecar})
    return dict(zip(("plain", "default", "visibility"), shots))


@pytest.mark.slow
@pytest.mark.parametrize("config", ("plain", "default", "visibility"))
def test_threejs_hides_the_nested_box(drawn, config):
    shot = drawn[config]
    # the shot's view is three.js's, in its y-up world: the geometry's frame is Blender's
    to_view = shot.view @ np.block([[TO_Y_UP, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]])
    to_clip = perspective(CAMERA, W / H) @ to_view
    expected, nested_alone = grey(shot, to_view, to_clip)
    got = shot.pixels[..., 0].astype(np.float64)
    right = np.abs(got - expected) <= 3
    # the nested sphere's shade where the truth's differs from it by far more than the rounding
    shown = (np.abs(got - nested_alone) <= 3) & (np.abs(expected - nested_alone) > 12) & (nested_alone > 0)
    assert shown.sum() == 0, f"{config}: the nested box shows on {shown.sum()} px"
    assert right.mean() >= 0.98, f"{config}: {right.mean():.3f} of the pixels shaded as the geometry"

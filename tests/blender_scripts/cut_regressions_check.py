"""Run in a Blender (Debian's 3.4 program in the background, or the bpy module): piles of randomly
rotated boxes drawn by the viewport preview offscreen without the hidden-box cut, with its
pre-pass in one pass, and with its resolved passes (Blender 4.2 and later), each cut forced
whatever the depth of the boxes (tests/test_cut_regressions.py says what each scene is for).

Usage: blender --background --factory-startup --python cut_regressions_check.py -- PACKAGE_PARENT OUT.npz
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402
from boxmarch.preview import occlusion, resolve  # noqa: E402

boxmarch.register()
W, H = 200, 150
SIZE = np.array([0.3, 0.25, 0.2])
COUNT = 300
# name: (vertices' offset from the object's origin, every n-th box opened, camera distance, lens (mm),
# near plane); the orthographic camera's (ortho_scale, far plane) in ORTHO
SCENES = {"pile": (0.0, 0, 3.5, 50.0, 0.1), "offset_100": (100.0, 0, 3.5, 50.0, 0.1),
          "offset_1000": (1000.0, 0, 3.5, 50.0, 0.1), "open": (0.0, 3, 3.5, 50.0, 0.1),
          "distant": (0.0, 0, 40.0, 50.0 * 40.0 / 3.5 / 2.0, 0.01),
          "mid_depth_ortho": (0.0, 0, 1e5, 50.0, 1e3), "squashed": (0.0, 0, 3.5, 50.0, 0.1)}
# far plane 2 x distance - near: the pile at window depth 0.5, where bm_depth_rounding pushes its occluders
# back by almost nothing (their clip z is ~0) and its depth spans fewer float steps than its boxes' faces lie apart
ORTHO = {"mid_depth_ortho": (2.6, 2e5 - 1e3)}
# the object's scale: squashed across the view, so its boxes' faces turn edge-on and a pixel spans
# 3.3 times as many object units across x as along the object-to-clip matrix's y row (the three.js
# cut regressions' "squashed" pile lost pixels to that on SwiftShader; llvmpipe's finer sub-pixel
# grid does not show it: the scene passes with the old rule too)
SCALE = {"squashed": (0.3, 1.0, 1.4)}


def build(offset, opened, distance, lens, near, ortho=None, scale=(1.0, 1.0, 1.0)):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    rng = np.random.default_rng(1)
    centres = rng.uniform(-0.8, 0.8, (COUNT, 3)) + offset
    rotations = scenes.random_rotations(COUNT, rng)
    positions, _edges, starts, sizes, corners = scenes.box_arrays(centres, np.tile(SIZE, (COUNT, 1)), rotations)
    faces = [corners[s:s + n] for s, n in zip(starts, sizes)]
    if opened:  # the first face of every opened-th box deleted
        faces = [face for k, face in enumerate(faces) if k % (6 * opened)]
    sizes = np.array([len(f) for f in faces], np.int32)
    mesh = mesh_io.new_mesh("pile", positions, np.r_[0, np.cumsum(sizes)[:-1]].astype(np.int32), sizes,
                            np.concatenate(faces).astype(np.int32))
    ob = bpy.data.objects.new("pile", mesh)
    ob.scale = scale
    scene.collection.objects.link(ob)
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    ob.boxmarch.preview = True
    ob.boxmarch.sdf = "BOX"
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    target = Vector((offset,) * 3)
    camera.location = target + Vector((0.4, -3.5, 0.6)) * (distance / 3.5)
    camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.lens = lens
    camera.data.clip_start, camera.data.clip_end = near, 100.0 if distance < 10.0 else 1000.0
    if ortho:
        camera.data.type = "ORTHO"
        camera.data.ortho_scale, camera.data.clip_end = ortho
    scene.camera = camera
    bpy.context.view_layer.update()
    return scene, camera, centres, rotations, ob


result = {"resolved_available": resolve.available()}
occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = 0.0, 0.0  # each cut whatever the depth of the boxes
for name, settings in SCENES.items():
    scene, camera, centres, rotations, ob = build(*settings, ORTHO.get(name), SCALE.get(name, (1.0, 1.0, 1.0)))
    if name == "pile":
        result.update(centres=centres, rotations=rotations, matrix_world=np.array(ob.matrix_world))
        result["view"], result["projection"] = preview.camera_matrices(scene, camera, W, H)
    cuts = {"off": (False, False), "one_pass": (True, False)}
    if resolve.available():
        cuts["resolved"] = (True, True)
    for cut, (occluders, resolved) in cuts.items():
        occlusion.ENABLED, resolve.ENABLED = occluders, resolved
        result[f"{name}_{cut}_rgba"], result[f"{name}_{cut}_depth"] = preview.render(scene, camera, W, H)
occlusion.ENABLED, resolve.ENABLED = True, True

np.savez_compressed(out_path, **result)
sys.stdout.flush()
os._exit(0)  # PyPI's bpy 4.2/4.5 crash at exit once an add-on registered classes (docs/PLATFORMS.md)

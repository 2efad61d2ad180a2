"""Writes docs/preview_pose.png: the raymarch preview following a posed armature (offscreen, Mesa
llvmpipe). A chain of 258 links wound around a 3-bone arm, baked at rest, every link rigidly
weighted to the bone under it, the arm bent 40 degrees at each joint. Left: the NORMAL_FRAME layout
(the frame rides in the normal and tangent, which skinning turns): every link stays in its box.
Right: CLASSIC (the frame rides in UV maps, which no skinning turns): the links slide out of their
boxes, as in any engine.

Usage: blender --background --factory-startup --python scripts/preview_pose_picture.py -- PACKAGE_PARENT OUT.png
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import chain_arm  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 640, 540

chain, rig, links = chain_arm.build(bpy, scene)
chain.boxmarch.sdf = "LINK"
chain.boxmarch.preview = True
chain_arm.pose(rig)

bpy.context.view_layer.update()
posed = mesh_io.read_positions(chain.evaluated_get(bpy.context.evaluated_depsgraph_get()).data)
low, high = posed.min(axis=0), posed.max(axis=0)  # frame the posed arm, seen from +x
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
target = mathutils.Vector(((low + high) / 2).tolist())
camera.location = target + mathutils.Vector((1.0, -0.25, 0.15)) * 1.25 * float(np.linalg.norm(high - low))
camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.lens = 40.0
scene.camera = camera
bpy.context.view_layer.update()

panels = []
for layout in ("NORMAL_FRAME", "CLASSIC"):
    chain.boxmarch.layout = layout
    rgba, _depth = preview.render(scene, camera, W, H)
    alpha = np.clip(rgba[..., 3:4], 0.0, 1.0)
    panels.append(np.clip(rgba[..., :3], 0.0, 1.0) * alpha + np.float32(0.08) * (1.0 - alpha))
picture = np.concatenate([panels[0], np.full((H, 4, 3), 0.5, np.float32), panels[1]], axis=1)
image = bpy.data.images.new("preview_pose", picture.shape[1], H, alpha=True)
pixels = np.ones((H, picture.shape[1], 4), np.float32)
pixels[..., :3] = picture[::-1]  # Blender stores rows bottom-up
image.pixels.foreach_set(pixels.ravel())
image.filepath_raw = out_path
image.file_format = "PNG"
image.save()
print("preview_pose_picture: wrote", out_path, f"({links} links)")

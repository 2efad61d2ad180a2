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

import boxmarch  # noqa: E402
from boxmarch import preview  # noqa: E402

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

camera = chain_arm.camera_on_posed_arm(bpy, scene, chain)
renders = []
for layout in ("NORMAL_FRAME", "CLASSIC"):
    chain.boxmarch.layout = layout
    renders.append(preview.render(scene, camera, W, H)[0])
chain_arm.save_side_by_side(bpy, *renders, out_path)
print("preview_pose_picture: wrote", out_path, f"({links} links)")

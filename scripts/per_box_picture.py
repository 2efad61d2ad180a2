"""Writes docs/per_box.png: the chain on the posed arm (scripts/chain_arm.py) with every link its
own shape and material, in the raymarch preview (offscreen, Mesa llvmpipe). The links are painted
boxmarch_shape (chain link, torus, sphere in turn: 6, 6, 5, 6, 6, 1 repeating) and
boxmarch_material (one per bone, the top third counting on), baked with the CHAIN parent rule
(each link the child of the one before). Left: one preset for every box (LINK); right: Per-Box
Shape, coloured by material.

Usage: blender --background --factory-startup --python scripts/per_box_picture.py -- PACKAGE_PARENT OUT.png
   or: python3 scripts/per_box_picture.py -- PACKAGE_PARENT OUT.png   (the bpy module)
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
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
mesh = chain.data
shapes = np.resize([6, 6, 5, 6, 6, 1], links).astype(np.int32)
centres = mesh_io.read_positions(mesh).reshape(links, 8, 3).mean(axis=1)
materials = np.minimum((centres[:, 2] // (chain_arm.ARM / 3)).astype(int), 2)
materials[centres[:, 2] > chain_arm.ARM * 0.8] = 3
mesh.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set("value", np.repeat(shapes, 8))
mesh.attributes.new("boxmarch_material", "INT", "POINT").data.foreach_set("value", np.repeat(materials, 8).astype(np.int32))
assert bpy.ops.boxmarch.bake(sort_axes_by_extent=True, hierarchy="CHAIN") == {"FINISHED"}
chain.boxmarch.layout = "NORMAL_FRAME"
chain.boxmarch.preview = True
chain_arm.pose(rig)

camera = chain_arm.camera_on_posed_arm(bpy, scene, chain)
renders = []
for sdf, by_material in (("LINK", False), ("PER_BOX", True)):
    chain.boxmarch.sdf = sdf
    chain.boxmarch.colour_by_material = by_material
    renders.append(preview.render(scene, camera, W, H)[0])
chain_arm.save_side_by_side(bpy, *renders, out_path)
print("per_box_picture: wrote", out_path)

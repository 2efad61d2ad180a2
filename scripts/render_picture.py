"""Renders docs/demo.png with Debian's Blender (Workbench): a world of baked boxes, shaded by the
baked BoxOffset colour (each box's offsets point at its centre, so every box shows the same
gradient in its own frame, whatever its rotation).
Usage: blender -b --factory-startup --python scripts/render_picture.py -- PACKAGE_PARENT OUT.png"""
import math
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_homefile(use_empty=True)
rng = np.random.default_rng(3)
count = 3000
centres = rng.uniform(-12, 12, (count, 3)) * [1.6, 1.0, 0.5]
positions, _, face_starts, face_sizes, corner_verts = scenes.box_arrays(
    centres, rng.uniform(0.2, 1.6, (count, 3)), scenes.random_rotations(count, rng))
mesh = mesh_io.new_mesh("BoxWorld", positions, face_starts, face_sizes, corner_verts)
ob = bpy.data.objects.new("BoxWorld", mesh)
bpy.context.scene.collection.objects.link(ob)
mesh_io.prepare_bake(mesh, mesh_io.BakeSettings()).write()
mesh.color_attributes.active_color = mesh.color_attributes["BoxOffset"]

camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
bpy.context.scene.collection.objects.link(camera)
camera.location = (0.0, -38.0, 16.0)
camera.rotation_euler = (math.radians(68), 0.0, 0.0)
scene = bpy.context.scene
scene.camera = camera
scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.light = "STUDIO"
scene.display.shading.color_type = "VERTEX"
scene.display.shading.show_cavity = True
scene.render.resolution_x, scene.render.resolution_y = 960, 540
scene.render.filepath = argv[1]
bpy.ops.render.render(write_still=True)

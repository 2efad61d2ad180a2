"""Run inside a Blender program: save a .blend holding random boxes (unbaked) and a camera.
Usage: blender -b --python make_boxes.py -- PACKAGE_PARENT OUT.blend COUNT SEED"""
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])

import bpy  # noqa: E402

from boxmarch import mesh_io, scenes  # noqa: E402

bpy.ops.wm.read_homefile(use_empty=True)
(positions, _, face_starts, face_sizes, corner_verts), *_ = scenes.random_boxes(
    int(argv[2]), seed=int(argv[3]), spread=10.0, size_range=(0.5, 3.0))
ob = bpy.data.objects.new("Boxes", mesh_io.new_mesh("Boxes", positions, face_starts, face_sizes, corner_verts))
bpy.context.scene.collection.objects.link(ob)
bpy.context.scene.collection.objects.link(bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera")))
bpy.ops.wm.save_as_mainfile(filepath=argv[1])

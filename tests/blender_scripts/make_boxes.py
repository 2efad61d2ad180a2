"""Run inside a Blender program: save a .blend holding random boxes (unbaked) and a camera; with
MESSY, also an object "Messy" of 10 boxes, 3 exact duplicates of the first three, and one box
whose corner 0 is split into two vertices 1e-5 apart (one submesh still).
Usage: blender -b --python make_boxes.py -- PACKAGE_PARENT OUT.blend COUNT SEED [MESSY]"""
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from boxmarch import mesh_io, scenes  # noqa: E402

bpy.ops.wm.read_homefile(use_empty=True)
(positions, _, face_starts, face_sizes, corner_verts), *_ = scenes.random_boxes(
    int(argv[2]), seed=int(argv[3]), spread=10.0, size_range=(0.5, 3.0))
ob = bpy.data.objects.new("Boxes", mesh_io.new_mesh("Boxes", positions, face_starts, face_sizes, corner_verts))
bpy.context.scene.collection.objects.link(ob)
bpy.context.scene.collection.objects.link(bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera")))
if len(argv) > 4 and argv[4] == "MESSY":
    (p, _, starts, sizes, corners), *_ = scenes.random_boxes(10, seed=99, spread=10.0, size_range=(0.5, 3.0))
    p = np.concatenate([p, p[:24], p[24:25] + np.float32(1e-5)])  # 3 duplicate boxes, 1 split corner
    corners = np.concatenate([corners, corners[:72] + 80]).astype(np.int32)
    corners[3 * 24] = 104  # box 3's first face (-x) uses the split copy of its corner 0 (vertex 24)
    starts = np.arange(0, len(corners), 4, dtype=np.int32)
    sizes = np.full(len(starts), 4, np.int32)
    messy = bpy.data.objects.new("Messy", mesh_io.new_mesh("Messy", p, starts, sizes, corners))
    bpy.context.scene.collection.objects.link(messy)
bpy.ops.wm.save_as_mainfile(filepath=argv[1])

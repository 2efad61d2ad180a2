"""Run inside a Blender program: bake random boxes with the add-on and write what the stored data
decodes to. Usage: blender -b --python bake_check.py -- PACKAGE_PARENT OUT_JSON"""
import json
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_homefile(use_empty=True)
(positions, edges, face_starts, face_sizes, corner_verts), centres, sizes, _ = scenes.random_boxes(200, seed=7, spread=50)
mesh = mesh_io.new_mesh("boxes", positions, face_starts, face_sizes, corner_verts)
ob = bpy.data.objects.new("boxes", mesh)
bpy.context.scene.collection.objects.link(ob)
ob.select_set(True)
bpy.context.view_layer.objects.active = ob
result = bpy.ops.boxmarch.bake(encoding=argv[2] if len(argv) > 2 else "FLOAT_COLOR")

raw = mesh.color_attributes["BoxOffset"].data_type == "BYTE_COLOR"
colour = np.empty(len(mesh.vertices) * 4, np.float32)
mesh.color_attributes["BoxOffset"].data.foreach_get("color_srgb" if raw else "color", colour)
colour = colour.reshape(-1, 4).astype(np.float64)
quat = []
for name in ("BoxQuatXY", "BoxQuatZW"):
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers[name].data.foreach_get("uv", uv)
    quat.append(uv.reshape(-1, 2))
q = np.concatenate(quat, axis=1).astype(np.float64)
f = (colour[corner_verts, :3] * 2 - 1) / colour[corner_verts, 3:4]
u, w = q[:, :3], q[:, 3:4]
origins = positions[corner_verts].astype(np.float64) + f + 2 * np.cross(u, np.cross(u, f) + w * f)
error = np.linalg.norm(origins - np.repeat(centres, 24, axis=0), axis=1) / np.repeat(sizes.max(axis=1) / 2, 24)
with open(argv[1], "w") as out:
    json.dump({"result": sorted(result), "version": list(bpy.app.version),
               "uv_layers": [uv.name for uv in mesh.uv_layers], "max_relative_error": float(error.max()),
               "alpha_max": float(colour[:, 3].max())}, out)

"""Run inside Debian's Blender (background): bakes a box scene, renders it through the viewport
preview offscreen (GPU, llvmpipe here) and writes the images with the scene's ground truth.

Usage: blender --background --factory-startup --python preview_check.py -- PACKAGE_PARENT OUT.npz
"""
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402
from boxmarch.preview import draw  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 320, 240

# 24 randomly turned boxes, some overlapping, seen by a perspective camera.
(positions, _edges, face_starts, face_sizes, corner_verts), centres, sizes, rotations = \
    scenes.random_boxes(24, seed=7, spread=2.5, size_range=(0.4, 1.6))
mesh = mesh_io.new_mesh("boxes", positions, face_starts, face_sizes, corner_verts)
boxes = bpy.data.objects.new("boxes", mesh)
scene.collection.objects.link(boxes)
boxes.location = (0.3, -0.2, 0.1)
boxes.rotation_euler = (0.2, 0.1, 0.4)
bpy.context.view_layer.objects.active = boxes
boxes.select_set(True)
assert bpy.ops.boxmarch.bake() == {"FINISHED"}

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = (7.5, -8.0, 6.0)
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start, camera.data.clip_end = 0.5, 40.0
scene.camera = camera
bpy.context.view_layer.update()

result = {"centres": centres, "sizes": sizes, "rotations": rotations,
          "matrix_world": np.array(boxes.matrix_world), "color": np.array(boxes.color)}
view, projection = preview.camera_matrices(scene, camera, W, H)
result["view"], result["projection"] = view, projection

boxes.boxmarch.preview = True
for sdf in ("BOX", "SPHERE", "ROUNDED_BOX"):
    boxes.boxmarch.sdf = sdf
    for output in ("SHADED", "NORMAL"):
        rgba, depth = preview.render(scene, camera, W, H, output=output)
        result[f"{sdf}_{output}_rgba"], result[f"{sdf}_{output}_depth"] = rgba, depth

# A user SDF: the same sphere written by hand must give the SPHERE preset's image.
text = bpy.data.texts.new("my_sphere.glsl")
text.write("float map(vec3 p)\n{\n  return sd_sphere(p, min3(box_half));\n}\n")
boxes.boxmarch.sdf = "USER"
boxes.boxmarch.user_text = text.name
result["USER_SHADED_rgba"], result["USER_SHADED_depth"] = preview.render(scene, camera, W, H)
result["user_error"] = str(draw.errors.get(boxes.name))

# A broken user SDF: the error names the line, and only the outline is drawn.
broken = bpy.data.texts.new("broken.glsl")
broken.write("float map(vec3 p)\n{\n  float r = min3(box_half);\n  return lenght(p) - r;\n}\n")
boxes.boxmarch.user_text = broken.name
result["BROKEN_rgba"], result["BROKEN_depth"] = preview.render(scene, camera, W, H)
result["broken_error"] = str(draw.errors.get(boxes.name))

# Composition by depth with an ordinary mesh: a ground plane cutting through the spheres.
boxes.boxmarch.sdf = "SPHERE"
bpy.ops.mesh.primitive_plane_add(size=12.0, location=(0.0, 0.0, 0.2))
plane = bpy.context.active_object
result["COMPOSITE_rgba"], result["COMPOSITE_depth"] = preview.render(scene, camera, W, H)
boxes.hide_viewport = True
result["PLANE_rgba"], result["PLANE_depth"] = preview.render(scene, camera, W, H)
result["plane_matrix"] = np.array(plane.matrix_world)

np.savez_compressed(out_path, **result)
print("preview_check: wrote", out_path)

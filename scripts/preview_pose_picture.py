"""Writes docs/preview_pose.png: the raymarch preview following a posed armature (offscreen, Mesa
llvmpipe). A chain of about 250 links wound around a 3-bone arm, baked at rest, every link rigidly
weighted to the bone under it, the arm bent 40 degrees at each joint. Left: the NORMAL_FRAME layout
(the frame rides in the normal and tangent, which skinning turns): every link stays in its box.
Right: CLASSIC (the frame rides in UV maps, which no skinning turns): the links slide out of their
boxes, as in any engine.

Usage: blender --background --factory-startup --python scripts/preview_pose_picture.py -- PACKAGE_PARENT OUT.png
"""
import math
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 640, 540
RADIUS, ARM, TURNS = 0.6, 9.0, 20      # a helix of this radius and this many turns around an arm this long (3 bones)
LINK = np.array([0.46, 0.23, 0.06])    # link length, width, wire thickness

# The helix around the arm's axis (z), links spaced at 0.78 of their length along it, each turned
# 90 degrees about its own axis from the last (a chain).
climb = ARM / (2 * math.pi * TURNS)
step = 0.78 * LINK[0] / math.hypot(RADIUS, climb)
t = step * np.arange(int(2 * math.pi * TURNS / step)) + 0.2
t = t[climb * t < ARM - 0.2]
centres = np.column_stack([RADIUS * np.cos(t), RADIUS * np.sin(t), climb * t])
tangent = np.column_stack([-RADIUS * np.sin(t), RADIUS * np.cos(t), np.full(len(t), climb)])
tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
radial = np.column_stack([np.cos(t), np.sin(t), np.zeros(len(t))])
across = np.where((np.arange(len(t)) % 2)[:, None] == 0, radial, np.cross(tangent, radial))
rotations = np.stack([tangent, np.cross(across, tangent), across], axis=2)  # columns: local x, y, z
positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, np.tile(LINK, (len(t), 1)),
                                                                             rotations)
chain = bpy.data.objects.new("chain", mesh_io.new_mesh("chain", positions, face_starts, face_sizes, corner_verts))
scene.collection.objects.link(chain)
chain.color = (0.85, 0.65, 0.3, 1.0)

rig = bpy.data.objects.new("arm", bpy.data.armatures.new("arm"))
scene.collection.objects.link(rig)
bpy.context.view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
parent = None
for k in range(3):
    bone = rig.data.edit_bones.new(f"bone{k}")
    bone.head, bone.tail = (0.0, 0.0, ARM / 3 * k), (0.0, 0.0, ARM / 3 * (k + 1))
    if parent is not None:
        bone.parent, bone.use_connect = parent, True
    parent = bone
bpy.ops.object.mode_set(mode="OBJECT")
bone_of_link = np.minimum((centres[:, 2] // (ARM / 3)).astype(int), 2)
for k in range(3):
    chain.vertex_groups.new(name=f"bone{k}").add(
        np.flatnonzero(np.repeat(bone_of_link, 8) == k).tolist(), 1.0, "REPLACE")
chain.modifiers.new("Armature", "ARMATURE").object = rig
for ob in scene.objects:
    ob.select_set(ob == chain)
bpy.context.view_layer.objects.active = chain
assert bpy.ops.boxmarch.bake(sort_axes_by_extent=True) == {"FINISHED"}
chain.boxmarch.sdf = "LINK"
chain.boxmarch.preview = True

for k in range(3):
    pose_bone = rig.pose.bones[f"bone{k}"]
    pose_bone.rotation_mode = "XYZ"
    pose_bone.rotation_euler = (math.radians(40.0), 0.0, 0.0)

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
print("preview_pose_picture: wrote", out_path, f"({len(t)} links)")

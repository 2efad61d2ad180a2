"""Run inside Blender (background; the Blender 3.4 program or the bpy 5.0 module): a 3-bone chain
rigging 36 boxes (12 rigidly weighted to each bone), baked at rest, previewed offscreen at rest,
posed by hand and posed by an action, in several layouts. Writes the images with the scene's
ground truth (rest boxes, bone rest matrices, the poses); tests/test_preview_pose.py computes the
posed boxes itself and renders them with the CPU reference.

Usage: blender --background --factory-startup --python preview_pose_check.py -- PACKAGE_PARENT OUT.npz
"""
import math
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402
from boxmarch.preview import draw, mesh_data  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 320, 240
BOXES_PER_BONE, BONE_LENGTH = 12, 2.0
# Pose A (by hand) and pose B (an action): per bone, a 40 degree turn about a bone-local axis
# (bone y runs along the bone).
POSE_A = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0))
POSE_B = ((0.0, 0.0, 1.0), (-1.0, 0.0, 0.0), (0.0, 0.0, -1.0))
ANGLE = math.radians(40.0)

# Boxes along a chain running up the mesh's local z, 12 per bone segment.
rng = np.random.default_rng(11)
count = 3 * BOXES_PER_BONE
bone_of_box = np.repeat(np.arange(3), BOXES_PER_BONE)
centres = np.column_stack([rng.uniform(-0.7, 0.7, count), rng.uniform(-0.7, 0.7, count),
                           BONE_LENGTH * bone_of_box + rng.uniform(0.25, BONE_LENGTH - 0.25, count)])
sizes = rng.uniform(0.3, 0.7, (count, 3))
rotations = scenes.random_rotations(count, rng)
positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, sizes, rotations)
mesh = mesh_io.new_mesh("chain", positions, face_starts, face_sizes, corner_verts)
boxes = bpy.data.objects.new("chain", mesh)
scene.collection.objects.link(boxes)
boxes.location = (0.3, -0.2, 0.1)
boxes.rotation_euler = (0.2, 0.1, 0.4)

# The armature elsewhere (the Armature modifier works in its space), its bones through the boxes.
rig = bpy.data.objects.new("rig", bpy.data.armatures.new("rig"))
scene.collection.objects.link(rig)
rig.location = (-0.4, 0.5, 0.2)
rig.rotation_euler = (0.0, -0.3, 0.7)
bpy.context.view_layer.update()
mesh_to_rig = np.array(rig.matrix_world.inverted() @ boxes.matrix_world)
bpy.context.view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
parent = None
for k in range(3):
    bone = rig.data.edit_bones.new(f"bone{k}")
    bone.head = mathutils.Matrix(mesh_to_rig.tolist()) @ mathutils.Vector((0.0, 0.0, BONE_LENGTH * k))
    bone.tail = mathutils.Matrix(mesh_to_rig.tolist()) @ mathutils.Vector((0.0, 0.0, BONE_LENGTH * (k + 1)))
    if parent is not None:
        bone.parent, bone.use_connect = parent, True
    parent = bone
bpy.ops.object.mode_set(mode="OBJECT")

for k in range(3):  # rigid weights: every vertex of a box on its bone only
    group = boxes.vertex_groups.new(name=f"bone{k}")
    vertices = np.flatnonzero(np.repeat(bone_of_box, 8) == k)
    group.add(vertices.tolist(), 1.0, "REPLACE")
modifier = boxes.modifiers.new("Armature", "ARMATURE")
modifier.object = rig

for ob in scene.objects:
    ob.select_set(ob == boxes)
bpy.context.view_layer.objects.active = boxes
assert bpy.ops.boxmarch.bake() == {"FINISHED"}

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
target = mathutils.Vector((-0.2, -1.9, 2.8))  # the middle of the rest and posed chains
camera.location = target + mathutils.Vector((8.0, -9.0, 3.0))
camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start, camera.data.clip_end = 0.5, 30.0
scene.camera = camera
bpy.context.view_layer.update()

result = {"centres": centres, "sizes": sizes, "rotations": rotations, "bone_of_box": bone_of_box,
          "matrix_world": np.array(boxes.matrix_world), "mesh_to_rig": mesh_to_rig,
          "bone_rest": np.array([np.array(rig.data.bones[f"bone{k}"].matrix_local) for k in range(3)]),
          "pose_a": np.array(POSE_A), "pose_b": np.array(POSE_B), "angle": ANGLE}
result["view"], result["projection"] = preview.camera_matrices(scene, camera, W, H)
boxes.boxmarch.preview = True
boxes.boxmarch.sdf = "ROUNDED_BOX"


def render_layouts(name, layouts):
    for layout in layouts:
        if boxes.boxmarch.layout != layout:  # setting it (even unchanged) tags the mesh: everything is read again
            boxes.boxmarch.layout = layout
        result[f"{name}_{layout}_rgba"], result[f"{name}_{layout}_depth"] = preview.render(scene, camera, W, H)
    result[f"{name}_skipped"] = "; ".join(preview.last_skipped)


def set_pose(axes):
    for k, axis in enumerate(axes):
        pose_bone = rig.pose.bones[f"bone{k}"]
        pose_bone.rotation_mode = "QUATERNION"
        pose_bone.rotation_quaternion = mathutils.Quaternion(axis, ANGLE)


render_layouts("REST", ("NORMAL_FRAME",))
rest_mesh_entry = draw.cached_mesh(mesh.name_full, "NORMAL_FRAME")
rest_weights = draw.posed_state(boxes.name_full).weights

# Pose A by hand: the depsgraph handler marks the pose stale; what the pose does not change is kept.
set_pose(POSE_A)
bpy.context.view_layer.update()
render_layouts("POSE_A", ("NORMAL_FRAME",))
result["mesh_entry_kept"] = draw.cached_mesh(mesh.name_full, "NORMAL_FRAME") is rest_mesh_entry
result["weights_kept"] = draw.posed_state(boxes.name_full).weights is rest_weights
# The decoded-vector overlay of the posed data: each vertex + its skinned frame applied to f, the
# CPU decode of what the shader receives; drawn once to run the overlay's path.
drawn = draw.posed_state(boxes.name_full).drawn
result["POSE_A_decoded_origins"] = mesh_data.vector_lines(drawn.positions, drawn.offsets, drawn.frame())[1][1::2]
boxes.boxmarch.show_vectors = True
render_layouts("VECTORS", ("NORMAL_FRAME",))
boxes.boxmarch.show_vectors = False
render_layouts("POSE_A", ("NORMAL_COLOR", "CLASSIC", "UV_FRAME"))

# Pose B by an action, reached by changing frames only (the frame-change handler).
for frame, axes in ((1, POSE_A), (11, POSE_B)):
    set_pose(axes)
    for k in range(3):
        rig.pose.bones[f"bone{k}"].keyframe_insert("rotation_quaternion", frame=frame)
scene.frame_set(1)
render_layouts("ACTION_1", ("NORMAL_FRAME",))
scene.frame_set(11)
render_layouts("ACTION_11", ("NORMAL_FRAME",))

# A bone renamed (Blender renames its vertex group and the action's paths too): weights read again.
rig.data.bones["bone1"].name = "forearm"
bpy.context.view_layer.update()
render_layouts("RENAMED", ("NORMAL_FRAME",))

# The last bone no longer deforms: Blender leaves its vertices at rest, and so must the frames.
rig.data.bones["bone2"].use_deform = False
bpy.context.view_layer.update()
render_layouts("BONE2_OFF", ("NORMAL_FRAME",))
rig.data.bones["bone2"].use_deform = True

# An Armature modifier the preview cannot follow: that object is left out with the reason.
modifier.use_bone_envelopes = True
bpy.context.view_layer.update()
render_layouts("ENVELOPES", ("NORMAL_FRAME",))
result["envelopes_error"] = str(draw.errors.get(boxes.name))

np.savez_compressed(out_path, **result)
print("preview_pose_check: wrote", out_path)
sys.stdout.flush()
sys.stderr.flush()
os._exit(0)  # the bpy modules 4.2 and 4.5 segfault at interpreter exit once the add-on registered

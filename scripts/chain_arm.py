"""The chain-on-an-arm scene of the posed pictures (scripts/preview_pose_picture.py and
per_box_picture.py for the viewport preview, scripts/threejs_pose_picture.py for three.js): a chain
of links wound in a helix around a 3-bone arm up z, baked at rest, every link rigidly weighted to
the bone under it; and the two steps those pictures share: a camera on the posed arm and two
preview renders saved side by side."""
import math

import numpy as np

RADIUS, ARM, TURNS = 0.6, 9.0, 25      # a helix of this radius and this many turns around an arm this long (3 bones)
LINK = np.array([0.46, 0.23, 0.06])    # link length, width, wire thickness
BONE_TURN = math.radians(40.0)         # the pose: each joint bent this much about x


def chain_geometry(radius=RADIUS, turns=TURNS, link=LINK):
    """(centres, rotations) of the links (length, width, thickness ``link``): along a helix of
    ``radius`` and ``turns`` turns, spaced at 0.78 of their length, each turned 90 degrees about
    its own axis from the last (a chain); rotation columns: along the link, across it, its
    thickness (which the default bake need not make local x, y, z: the presets read the box's
    axes by extent)."""
    climb = ARM / (2 * math.pi * turns)
    step = 0.78 * link[0] / math.hypot(radius, climb)
    t = step * np.arange(int(2 * math.pi * TURNS / step)) + 0.2
    t = t[climb * t < ARM - 0.2]
    centres = np.column_stack([radius * np.cos(t), radius * np.sin(t), climb * t])
    tangent = np.column_stack([-radius * np.sin(t), radius * np.cos(t), np.full(len(t), climb)])
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    radial = np.column_stack([np.cos(t), np.sin(t), np.zeros(len(t))])
    across = np.where((np.arange(len(t)) % 2)[:, None] == 0, radial, np.cross(tangent, radial))
    return centres, np.stack([tangent, np.cross(across, tangent), across], axis=2)


def build(bpy, scene, radius=RADIUS, turns=TURNS, link=LINK):
    """The chain object (Armature modifier on the arm), baked with every default, and the arm, both
    at the origin; the chain as chain_geometry makes it. Returns (chain object, arm object, link
    count)."""
    from boxmarch import mesh_io, scenes

    centres, rotations = chain_geometry(radius, turns, link)
    positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(
        centres, np.tile(link, (len(centres), 1)), rotations)
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
    chain.parent = rig  # as Ctrl+P > With Empty Groups leaves it: the glTF exporter wants the armature as parent
    for ob in scene.objects:
        ob.select_set(ob == chain)
    bpy.context.view_layer.objects.active = chain
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    return chain, rig, len(centres)


def pose(rig):
    """Bend each joint by BONE_TURN about x (the bones' local x is world x: they run up z)."""
    for k in range(3):
        pose_bone = rig.pose.bones[f"bone{k}"]
        pose_bone.rotation_mode = "XYZ"
        pose_bone.rotation_euler = (BONE_TURN, 0.0, 0.0)


def camera_on_posed_arm(bpy, scene, chain):
    """A camera framing ``chain`` as posed (its evaluated mesh), seen from +x, made the scene's."""
    import mathutils

    from boxmarch import mesh_io

    bpy.context.view_layer.update()
    posed = mesh_io.read_positions(chain.evaluated_get(bpy.context.evaluated_depsgraph_get()).data)
    low, high = posed.min(axis=0), posed.max(axis=0)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    target = mathutils.Vector(((low + high) / 2).tolist())
    camera.location = target + mathutils.Vector((1.0, -0.25, 0.15)) * 1.25 * float(np.linalg.norm(high - low))
    camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.lens = 40.0
    scene.camera = camera
    bpy.context.view_layer.update()
    return camera


def save_side_by_side(bpy, left_rgba, right_rgba, path):
    """Two preview renders ((H, W, 4), premultiplied by coverage) over a dark ground, a grey line
    between them, saved as a PNG at ``path``."""
    panels = []
    for rgba in (left_rgba, right_rgba):
        alpha = np.clip(rgba[..., 3:4], 0.0, 1.0)
        panels.append(np.clip(rgba[..., :3], 0.0, 1.0) * alpha + np.float32(0.08) * (1.0 - alpha))
    height = panels[0].shape[0]
    picture = np.concatenate([panels[0], np.full((height, 4, 3), 0.5, np.float32), panels[1]], axis=1)
    image = bpy.data.images.new("side_by_side", picture.shape[1], height, alpha=True)
    pixels = np.ones((height, picture.shape[1], 4), np.float32)
    pixels[..., :3] = picture[::-1]  # Blender stores rows bottom-up
    image.pixels.foreach_set(pixels.ravel())
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()

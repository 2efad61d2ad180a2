"""The demo's character (``python -m boxmarch demo``): a mannequin of boxes (every box a capsule in
the preview: limbs, torso and an egg of a head) on a 15-bone armature, wearing chains of links (a
necklace, a belt, a sash across the body and a chain wound round each arm), every box rigidly
weighted to one bone, and the pose the demo gives it (a hand on the hip, a wave, a bent knee).
Geometry and pose are plain arrays (NumPy only) so that scripts/threejs_picture.py turns three.js's
bones by the same POSE and the tests compute the posed boxes with their own forward kinematics;
``build`` makes the Blender objects."""
from __future__ import annotations

import math

import numpy as np

# name: (head, tail, parent) at rest, in Blender's axes: z up, the figure facing -y, its left +x.
# Parents come before their children.
BONES = {
    "pelvis": ((0.0, 0.0, 3.9), (0.0, 0.0, 4.5), None),
    "spine": ((0.0, 0.0, 4.5), (0.0, 0.0, 5.5), "pelvis"),
    "chest": ((0.0, 0.0, 5.5), (0.0, 0.0, 6.45), "spine"),
    "neck": ((0.0, 0.0, 6.45), (0.0, 0.0, 7.0), "chest"),
    "head": ((0.0, 0.0, 7.0), (0.0, 0.0, 7.95), "neck"),
}
for _side, _x in (("L", 1.0), ("R", -1.0)):
    BONES.update({
        f"upper_arm_{_side}": ((0.95 * _x, 0.0, 6.3), (2.45 * _x, 0.0, 6.3), "chest"),
        f"forearm_{_side}": ((2.45 * _x, 0.0, 6.3), (3.85 * _x, 0.0, 6.3), f"upper_arm_{_side}"),
        f"hand_{_side}": ((3.85 * _x, 0.0, 6.3), (4.3 * _x, 0.0, 6.3), f"forearm_{_side}"),
        f"thigh_{_side}": ((0.48 * _x, 0.0, 4.0), (0.48 * _x, 0.0, 2.1), "pelvis"),
        f"shin_{_side}": ((0.48 * _x, 0.0, 2.1), (0.48 * _x, 0.0, 0.35), f"thigh_{_side}"),
    })

# The pose: bone -> (axis, degrees): the bone turns about the axis (world axes, as the axis
# points with the armature at rest) through its head, carrying its children.
POSE = {
    "spine": ((0.0, 1.0, 0.0), -5.0),
    "chest": ((0.0, 0.0, 1.0), 10.0),
    "head": ((0.0, 1.0, 0.2), 14.0),
    "upper_arm_L": ((0.0, 1.0, 0.0), 52.0),     # down and out: the elbow stands off the side
    "forearm_L": ((0.0, 1.0, 0.0), 95.0),       # bent back: the hand on the hip
    "hand_L": ((0.0, 1.0, 0.0), 40.0),
    "upper_arm_R": ((0.0, 1.0, 0.25), 28.0),    # raised
    "forearm_R": ((0.0, 1.0, 0.0), 80.0),       # the forearm up: a wave
    "thigh_R": ((1.0, 0.0, -0.15), -14.0),      # forward
    "shin_R": ((1.0, 0.0, 0.0), 32.0),          # the knee bent
    "thigh_L": ((0.0, 1.0, 0.0), -5.0),
}

# The mannequin: (bone, centre, size) of each box at rest, axis-aligned; the capsule preset runs
# along a box's longest side with its smallest half-extent as radius (a cube: a sphere).
BODY = [
    ("head", (0.0, 0.0, 7.5), (0.95, 1.0, 1.15)),
    ("neck", (0.0, 0.0, 6.85), (0.38, 0.38, 0.7)),
    ("chest", (0.0, 0.0, 6.2), (2.0, 0.6, 0.6)),       # the shoulders
    ("chest", (0.0, 0.0, 5.85), (1.25, 1.2, 1.5)),
    ("spine", (0.0, 0.0, 5.0), (0.95, 0.9, 1.2)),
    ("pelvis", (0.0, 0.0, 4.15), (1.5, 0.8, 0.8)),
]
for _side, _x in (("L", 1.0), ("R", -1.0)):
    BODY += [
        (f"upper_arm_{_side}", (1.7 * _x, 0.0, 6.3), (1.55, 0.46, 0.46)),
        (f"forearm_{_side}", (3.12 * _x, 0.0, 6.3), (1.45, 0.38, 0.38)),
        (f"hand_{_side}", (4.02 * _x, 0.0, 6.3), (0.55, 0.42, 0.42)),
        (f"thigh_{_side}", (0.48 * _x, 0.0, 3.05), (0.62, 0.62, 2.0)),
        (f"shin_{_side}", (0.48 * _x, 0.0, 1.25), (0.5, 0.5, 1.85)),
        (f"shin_{_side}", (0.48 * _x, -0.3, 0.2), (0.4, 1.0, 0.4)),   # the foot
    ]

# object name -> (preview SDF, colour), as demo.png and demo_threejs.png draw them
LOOKS = {"Pebbles": ("CAPSULE", (0.45, 0.42, 0.38)), "Mannequin": ("CAPSULE", (0.6, 0.67, 0.78)),
         "Chains": ("LINK", (0.9, 0.66, 0.25))}
PICTURE_SIZE = (800, 600)
# Blender's axes; a lens of this many mm on a 36 mm sensor across the picture's width.
CAMERA = {"location": (5.6, -15.8, 7.6), "target": (0.0, 0.0, 4.3), "lens": 50.0}

LINK = np.array([0.42, 0.21, 0.05])  # link length, width, wire thickness
CLEARANCE = 0.13                     # how far a chain's centre line keeps off the body's surface


def capsules():
    """(a, b, radius) of the mannequin's capsules at rest: the segment and radius the capsule
    preset draws in each BODY box."""
    out = []
    for _bone, centre, size in BODY:
        axis = int(np.argmax(size))
        radius = min(s for k, s in enumerate(size) if k != axis) / 2
        reach = np.zeros(3)
        reach[axis] = max(size[axis] / 2 - radius, 0.0)
        out.append((np.array(centre) - reach, np.array(centre) + reach, radius))
    return out


def _segment_distance(points, a, b):
    """(distance to the segment a-b, the nearest point of it) for each of ``points``."""
    ab = b - a
    t = np.clip((points - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    nearest = a + t[:, None] * ab
    return np.linalg.norm(points - nearest, axis=1), nearest


def _clear_of_body(points):
    """``points`` pushed out of every capsule to CLEARANCE off its surface (a few passes: a push
    out of one can land in its neighbour)."""
    points = np.array(points, np.float64)
    for _ in range(4):
        for a, b, radius in capsules():
            distance, nearest = _segment_distance(points, a, b)
            inside = distance < radius + CLEARANCE
            away = (points[inside] - nearest[inside]) / np.maximum(distance[inside], 1e-9)[:, None]
            points[inside] = nearest[inside] + away * (radius + CLEARANCE)
    return points


def _links_along(points, closed, link=LINK):
    """(centres, rotations) of links along the dense polyline ``points``, spaced at 0.78 of their
    length, each turned 90 degrees about its own axis from the last (a closed loop gets an even
    count, so it closes alike). Rotation columns: along the link, across it, its thickness; the
    odd links lie flat on the surface (thickness along the way out from the body axis)."""
    ends = np.vstack([points, points[:1]]) if closed else points
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ends, axis=0), axis=1))])
    count = int(arc[-1] / (0.78 * link[0]))
    count -= count % 2 if closed else 0
    at = (np.arange(count) + 0.5) * arc[-1] / count

    def along(s):
        return np.column_stack([np.interp(s, arc, ends[:, k]) for k in range(3)])

    centres = along(at)
    tangent = along(at + 0.01) - along(at - 0.01)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # Out from the nearest body capsule's axis, made square to the chain.
    out = np.zeros_like(centres)
    best = np.full(len(centres), np.inf)
    for a, b, _radius in capsules():
        distance, nearest = _segment_distance(centres, a, b)
        closer = distance < best
        best[closer], out[closer] = distance[closer], (centres - nearest)[closer]
    out -= (out * tangent).sum(axis=1, keepdims=True) * tangent
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    across = np.where((np.arange(count) % 2)[:, None] == 0, np.cross(tangent, out), out)
    return centres, np.stack([tangent, np.cross(across, tangent), across], axis=2)


def _loop(centre, radii, tilt_about_y, dip, samples=400):
    """A closed loop round the body: an ellipse of ``radii`` (x, y) about ``centre``, tilted by
    ``tilt_about_y`` degrees, sagging ``dip`` at the front (-y)."""
    t = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    front = np.maximum(-np.sin(t), 0.0) ** 2
    local = np.column_stack([radii[0] * np.cos(t), radii[1] * np.sin(t), -dip * front])
    c, s = math.cos(math.radians(tilt_about_y)), math.sin(math.radians(tilt_about_y))
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return local @ turn.T + centre


def _arm_helix(side, turns=4.5, radius=0.3, samples=900):
    """A helix round one arm at rest, shoulder to wrist."""
    x = 1.0 if side == "L" else -1.0
    t = np.linspace(0.0, 2 * np.pi * turns, samples)
    along = np.linspace(1.15, 3.72, samples)
    return np.column_stack([x * along, radius * np.cos(t), 6.3 + radius * np.sin(t)])


# name -> (dense path at rest, closed, bones its links may ride)
TORSO = ("pelvis", "spine", "chest", "neck")


def chain_paths():
    return {
        "necklace": (_loop((0.0, 0.0, 6.62), (0.5, 0.45), 0.0, 0.75), True, TORSO),
        "belt": (_loop((0.0, 0.0, 4.5), (0.62, 0.55), 0.0, 0.12), True, TORSO),
        "sash": (_loop((0.0, 0.0, 5.35), (1.0, 0.6), -38.0, 0.0), True, TORSO),
        "arm_L": (_arm_helix("L"), False, ("upper_arm_L", "forearm_L")),
        "arm_R": (_arm_helix("R"), False, ("upper_arm_R", "forearm_R")),
    }


def links():
    """(centres, rotations, sizes, bone names) of every chain link at rest."""
    centres, rotations, bones = [], [], []
    for path, closed, riders in chain_paths().values():
        c, r = _links_along(_clear_of_body(path), closed)
        # Each link rides the nearest of its chain's bones: the arm chains bend at the elbow.
        distances = np.column_stack([_segment_distance(c, np.array(BONES[b][0]), np.array(BONES[b][1]))[0]
                                     for b in riders])
        centres.append(c)
        rotations.append(r)
        bones += [riders[k] for k in distances.argmin(axis=1)]
    centres = np.concatenate(centres)
    return centres, np.concatenate(rotations), np.tile(LINK, (len(centres), 1)), bones


def body():
    """(centres, rotations, sizes, bone names) of the mannequin's boxes at rest."""
    centres = np.array([c for _b, c, _s in BODY], np.float64)
    return centres, np.tile(np.eye(3), (len(BODY), 1, 1)), np.array([s for _b, _c, s in BODY]), [b for b, _c, _s in BODY]


def build(bpy, scene):
    """The armature 'Rig' (posed by POSE) and two baked-ready mesh objects on it, 'Mannequin' and
    'Chains', each box's 8 vertices weighted 1.0 to its bone; all at the world origin. Returns
    (rig, mannequin, chains)."""
    from mathutils import Matrix, Quaternion, Vector

    from . import mesh_io, scenes

    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    for name, (head, tail, parent) in BONES.items():
        bone = rig.data.edit_bones.new(name)
        bone.head, bone.tail = head, tail
        if parent is not None:
            bone.parent = rig.data.edit_bones[parent]
            bone.use_connect = bone.head == bone.parent.tail
    bpy.ops.object.mode_set(mode="OBJECT")
    for name, (axis, degrees) in POSE.items():
        pose_bone = rig.pose.bones[name]
        # The world axis in the bone's own rest frame (the armature stands at the origin).
        local = Matrix(rig.data.bones[name].matrix_local).to_3x3().inverted() @ Vector(axis).normalized()
        pose_bone.rotation_mode = "QUATERNION"
        pose_bone.rotation_quaternion = Quaternion(local, math.radians(degrees))
    objects = []
    for name, (centres, rotations, sizes, bones) in (("Mannequin", body()), ("Chains", links())):
        positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, sizes, rotations)
        ob = bpy.data.objects.new(name, mesh_io.new_mesh(name, positions, face_starts, face_sizes, corner_verts))
        scene.collection.objects.link(ob)
        bones = np.array(bones)
        for bone in sorted(set(bones)):
            ob.vertex_groups.new(name=bone).add(np.flatnonzero(np.repeat(bones == bone, 8)).tolist(), 1.0, "REPLACE")
        ob.modifiers.new("Armature", "ARMATURE").object = rig
        ob.parent = rig  # as Ctrl+P > With Empty Groups leaves it: the glTF exporter wants the armature as parent
        objects.append(ob)
    return (rig, *objects)

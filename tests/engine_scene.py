"""The scene the engine tests export: boxes of very different shapes whose geometry the tests know
independently of boxmarch (centres, sizes, rotations chosen here), and the checks that compare what
an engine received or drew with that geometry. Blender-free except :func:`baked_scene`."""
import functools
import re
from collections.abc import Mapping

import numpy as np

from boxmarch import scenes
from tests.engines import import_helpers

# Blender object space -> glTF / Godot (x, z, -y).
TO_Y_UP = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)


def mixed_boxes():
    """(centres, sizes, rotations) of 1 x 0.6 x 0.2, 0.02 x 0.02 x 0.1 and 5 x 5 x 5 boxes, in
    Blender's frame. Small boxes sit near the origin, where float32 positions are exact to well
    under 1e-5 of their half-extent, so the generating centres are a fair reference."""
    rng = np.random.default_rng(12)
    rotations = scenes.random_rotations(9, rng)
    centres = np.array([[-3.0, 0.0, 0.5], [-1.2, 1.0, -0.8], [1.0, -0.5, 1.2],        # 1 x 0.6 x 0.2
                        [0.05, 0.0, 0.0], [-0.05, 0.03, 0.02], [0.0, -0.04, -0.05],   # 0.02 x 0.02 x 0.1
                        [5.5, 2.0, -1.0], [-0.4, -2.0, -2.2], [2.2, 1.5, -2.0]])     # 5 x 5 x 5, 1 x 0.6 x 0.2 x 2
    sizes = np.array([[1.0, 0.6, 0.2]] * 3 + [[0.02, 0.02, 0.1]] * 3 + [[5.0, 5.0, 5.0]]
                     + [[1.0, 0.6, 0.2]] * 2)
    return centres, sizes, rotations


def baked_scene(bpy, name="Mixed"):
    """A baked object holding :func:`mixed_boxes` (default bake). Returns (object, centres,
    sizes, rotations)."""
    from boxmarch import mesh_io

    centres, sizes, rotations = mixed_boxes()
    arrays = scenes.box_arrays(centres, sizes, rotations)
    mesh = mesh_io.new_mesh(name, arrays[0], arrays[2], arrays[3], arrays[4], edges=arrays[1])
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    for other in bpy.context.selected_objects:
        other.select_set(False)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    return ob, centres, sizes, rotations


def box_of_vertex(engine_positions, centres, sizes, rotations, to_engine):
    """The generating box of every engine vertex: the box whose corner it is (the nearest corner,
    which must lie within float32 rounding of the vertex: 1e-6 of the scene's reach here)."""
    corners = np.concatenate([box_corners(c, s, r) for c, s, r in zip(centres, sizes, rotations)]) @ to_engine.T
    d = np.linalg.norm(engine_positions[:, None, :] - corners[None, :, :], axis=2)
    nearest = d.argmin(axis=1)
    assert d[np.arange(len(d)), nearest].max() < 1e-6 * max(1.0, np.abs(corners).max()), "a vertex is not at a box corner"
    return nearest // 8


def box_corners(centre, size, rotation):
    """(8, 3) corners of a box (Blender frame)."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    return centre + (signs * np.asarray(size) / 2) @ np.asarray(rotation).T


def decode_normal_frame(position, normal, tangent, offset, half):
    """The NORMAL_* layouts' decode as docs/ENGINES.md states it, in float64: axes x = tangent,
    z = normal, y = cross(z, x) * tangent.w; origin = position + x f.x + y f.y + z f.z.
    Returns (origins, axes (n, 3, 3) with columns x, y, z, half-extents)."""
    z, x = normal, tangent[:, :3]
    y = np.cross(z, x) * tangent[:, 3:4]
    axes = np.stack([x, y, z], axis=2)
    return position + np.einsum("nij,nj->ni", axes, offset), axes, half


def rotate(v, q):
    """v rotated by unit quaternions q (x, y, z, w), float64, row by row."""
    u, w = q[:, :3], q[:, 3:4]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def decode_uv_frame(positions, uvs):
    """docs/ENGINES.md, UV_FRAME: q = (UV1, UV2), f = (UV3, UV4.x), index = UV4.y, h = (UV5, UV6.x)."""
    q = np.concatenate(uvs[0:2], axis=1)
    f = np.concatenate([uvs[2], uvs[3][:, :1]], axis=1)
    h = np.concatenate([uvs[4], uvs[5][:, :1]], axis=1)
    x, y, z = (rotate(np.tile(e, (len(q), 1)), q) for e in np.eye(3))
    return positions + rotate(f, q), np.stack([x, y, z], axis=2), h, uvs[3][:, 1]


def frame_and_size_errors(origins, axes, half, box, centres, sizes, rotations, to_engine):
    """Worst (origin error / largest half-extent, axis error, half-extent error / half-extent):
    each decoded local axis must be +- one generating box axis, and its half-extent that axis's
    half size."""
    true_centre = centres[box] @ to_engine.T
    reach = sizes[box].max(axis=1) / 2
    origin_error = (np.linalg.norm(origins - true_centre, axis=1) / reach).max()
    true_axes = np.einsum("ij,njk->nik", to_engine, rotations[box])  # columns: box axes in engine frame
    cosines = np.abs(np.einsum("nik,nil->nkl", axes, true_axes))      # decoded k vs true l
    match = cosines.argmax(axis=2)
    axis_error = float((1.0 - cosines.max(axis=2)).max())
    true_half = np.take_along_axis(sizes[box] / 2, match, axis=1)
    half_error = float((np.abs(half - true_half) / true_half).max())
    return float(origin_error), axis_error, half_error


def convex_hull(points):
    """Convex hull (counter-clockwise, Andrew's monotone chain) of 2D points."""
    pts = sorted(map(tuple, np.asarray(points, float)))
    cross = lambda o, a, b: (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def silhouettes(shot, centres, sizes, rotations, to_engine, shrink=0.0):
    """Pixel-space convex silhouettes of the boxes (shrunk by ``shrink`` of their smallest
    half-extent on every side: the core a rounded box must cover), projected with the engine's
    camera."""
    out = []
    for c, s, r in zip(centres, sizes, rotations):
        inner = np.asarray(s, float) - 2 * shrink * min(s) / 2
        out.append(convex_hull(shot.project(box_corners(c, inner, r) @ to_engine.T)))
    return out


def rounded_box_mismatch(covered, shot, centres, sizes, rotations, to_engine, radius=0.1):
    """None when rounded boxes of radius ``radius`` x the smallest half-extent lie between each
    box and its core: every covered pixel within 1 px of a box silhouette, every pixel of a core
    (the box shrunk by the radius) covered; else what differs."""
    from tests.engines import coverage_mismatch, polygon_mask

    stray = coverage_mismatch(covered, silhouettes(shot, centres, sizes, rotations, to_engine))
    if stray is not None and "covered outside" in stray:
        return stray
    inside = np.zeros(covered.shape, bool)
    for polygon in silhouettes(shot, centres, sizes, rotations, to_engine, shrink=radius):
        inside |= polygon_mask(covered.shape, polygon)
    height, width = covered.shape
    return coverage_mismatch(covered | ~inside, [np.array([[0, 0], [width, 0], [width, height], [0, height]])])


class NotModelled(ValueError):
    """An import setting whose effect the modelled importer does not reproduce."""


def unity_import(settings):
    """Unity's FBX import, modelled from its documentation (docs/ENGINES.md), under the
    ModelImporter ``settings`` ({property: C# value}, as the shipped postprocessor sets them):
    x negated (right- to left-handed), UVs read as written, TexCoord2-7 stored as half floats
    by the Player's vertex compression unless Read/Write is on; the file's normals and tangents
    kept when both are imported. Settings whose effect is not modelled raise NotModelled."""
    if settings.get("meshCompression") != "ModelImporterMeshCompression.Off":
        raise NotModelled(f"Unity's Mesh Compression {settings.get('meshCompression')} is not modelled")
    return {"to_engine": np.diag([-1.0, 1.0, 1.0]) @ TO_Y_UP, "from_file": np.diag([-1.0, 1.0, 1.0]), "scale": 1.0,
            "flip_v": False, "half_float_channels": () if settings.get("isReadable") == "true" else (2, 3, 4, 5, 6),
            "file_frame": (settings.get("importNormals"), settings.get("importTangents"))
            == ("ModelImporterNormals.Import", "ModelImporterTangents.Import")}


def unreal_import(import_data, build):
    """Unreal's FBX import, modelled from its documentation and source (docs/ENGINES.md), under
    the FbxStaticMeshImportData ``import_data`` and MeshBuildSettings ``build`` the shipped
    script sets: the file's axes converted back to Z-up, then y negated, metres to centimetres
    (Convert Scene, Convert Scene Unit), every UV read as (u, 1 - v), UVs stored as half floats
    unless Use Full Precision UVs. Settings whose effect is not modelled raise NotModelled."""
    if not (import_data.get("convert_scene") and import_data.get("convert_scene_unit")):
        raise NotModelled("Unreal's import without Convert Scene and Convert Scene Unit is not modelled")
    if import_data.get("generate_lightmap_u_vs", True) or build.get("generate_lightmap_u_vs", True):
        raise NotModelled("Unreal's lightmap UV generation (it writes into a UV channel) is not modelled")
    return {"to_engine": np.diag([1.0, -1.0, 1.0]) * 100.0, "from_file": np.diag([1.0, -1.0, 1.0]) @ TO_Y_UP.T * 100.0,
            "scale": 100.0, "flip_v": True,
            "half_float_channels": () if build.get("use_full_precision_u_vs") else (1, 2, 3, 4, 5, 6)}


class BuiltOnFirstUse(Mapping):
    """A modelled import (the dict unity_import or unreal_import returns) built at its first
    lookup: building runs the engine helper (Unity's compiles C#: seconds), which modules that
    only import the name must not pay for."""

    def __init__(self, build):
        self._build = build

    @functools.cached_property
    def _model(self) -> dict:
        return self._build()

    def __getitem__(self, key):
        return self._model[key]

    def __iter__(self):
        return iter(self._model)

    def __len__(self):
        return len(self._model)


# The imports under what the shipped helpers set when run: the Unity postprocessor under mono on
# a boxmarch UNITY export, the Unreal script against the stub ``unreal`` module
# (tests/engines/import_helpers.py).
UNITY = BuiltOnFirstUse(lambda: unity_import(import_helpers.unity_settings()))
UNREAL = BuiltOnFirstUse(lambda: unreal_import(*import_helpers.unreal_settings()))
UV_NAMES = ["BoxQuatXY", "BoxQuatZW", "BoxOffsetXY", "BoxOffsetZIndex", "BoxHalfXY", "BoxHalfZ"]


def imported(raw, engine, half_float_channels=None):
    """(positions, UV1..UV6) as the engine stores them: positions through the importer's axes,
    each UV map flipped if the importer flips v, then rounded to half floats in
    ``half_float_channels`` (None: those of the engine's settings)."""
    if half_float_channels is None:
        half_float_channels = engine["half_float_channels"]
    positions = raw["position"] @ engine["from_file"].T
    uvs = []
    for channel, name in enumerate(UV_NAMES, start=1):
        uv = raw[name].astype(np.float32).copy()  # the engines keep float32 UVs
        if engine["flip_v"]:
            uv[:, 1] = np.float32(1.0) - uv[:, 1]
        if channel in half_float_channels:
            uv = uv.astype(np.float16).astype(np.float32)
        uvs.append(uv.astype(np.float64))
    return positions, uvs


def table_texels(tres_text):
    """float32 (texels, 4) of the RGBAFloat image in a Godot .tres (what Godot loads)."""
    data = re.search(r"PoolByteArray\(([^)]*)\)", tres_text).group(1)
    return np.frombuffer(bytes(int(b) for b in data.split(",")), "<f4").reshape(-1, 4).astype(np.float64)


# A skinned rig for the skinning tests: three bones up Blender's z axis (heads at 0, 2, 4), 12
# boxes of distinct sizes and rest rotations rigidly weighted to each, and a pose of 40 degree
# turns about world axes at each joint. Everything the tests compare with is computed here from
# these numbers (forward kinematics), not from what boxmarch or an engine computes.
RIG_BONES, RIG_BONE_LENGTH, RIG_BOXES_PER_BONE = 3, 2.0, 12
RIG_TURN_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # Blender world axes
RIG_TURN_ANGLE = np.radians(40.0)


def rig_boxes():
    """(centres, sizes, rotations, bone_of_box) of the rig's boxes at rest, Blender's frame."""
    rng = np.random.default_rng(13)
    count = RIG_BONES * RIG_BOXES_PER_BONE
    bone_of_box = np.repeat(np.arange(RIG_BONES), RIG_BOXES_PER_BONE)
    centres = np.column_stack([rng.uniform(-0.6, 0.6, count), rng.uniform(-0.6, 0.6, count),
                               RIG_BONE_LENGTH * bone_of_box + rng.uniform(0.3, RIG_BONE_LENGTH - 0.3, count)])
    sizes = rng.uniform(0.15, 0.6, (count, 3))
    return centres, sizes, scenes.random_rotations(count, rng), bone_of_box


def rig_heads():
    """(bones, 3) bone heads at rest, Blender world frame."""
    return np.array([[0.0, 0.0, RIG_BONE_LENGTH * k] for k in range(RIG_BONES)])


def axis_turn(axis, angle):
    """3 x 3 rotation by ``angle`` about the unit vector ``axis`` (Rodrigues)."""
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def bone_motions(axes=RIG_TURN_AXES, angle=RIG_TURN_ANGLE):
    """(bones, 4, 4) world motion of each bone from rest to the pose: joint k turns ``angle``
    about world axis ``axes[k]`` (as it points at rest) through its head, carrying the bones
    after it (forward kinematics of the chain)."""
    motion, out = np.eye(4), []
    for head, axis in zip(rig_heads(), axes):
        turn = np.eye(4)
        turn[:3, :3] = axis_turn(axis, angle)
        turn[:3, 3] = head - turn[:3, :3] @ head
        motion = motion @ turn
        out.append(motion)
    return np.array(out)


def posed_rig_boxes(axes=RIG_TURN_AXES, angle=RIG_TURN_ANGLE):
    """(centres, rotations) of the rig's boxes carried rigidly by their bones into the pose."""
    centres, _sizes, rotations, bone_of_box = rig_boxes()
    motion = bone_motions(axes, angle)[bone_of_box]
    return (np.einsum("nij,nj->ni", motion[:, :3, :3], centres) + motion[:, :3, 3],
            np.einsum("nij,njk->nik", motion[:, :3, :3], rotations))


def skinned_scene(bpy, name="Skinned"):
    """The rig in Blender: a baked mesh object of :func:`rig_boxes` (each box's vertices weighted
    1.0 to its bone's vertex group) with an Armature modifier on a 3-bone armature
    ``NAME-rig`` (bones ``bone0``..``bone2``, heads :func:`rig_heads`, both objects at the
    world origin). Returns (mesh object, armature object)."""
    from boxmarch import mesh_io

    centres, sizes, rotations, bone_of_box = rig_boxes()
    arrays = scenes.box_arrays(centres, sizes, rotations)
    ob = bpy.data.objects.new(name, mesh_io.new_mesh(name, arrays[0], arrays[2], arrays[3], arrays[4]))
    rig = bpy.data.objects.new(name + "-rig", bpy.data.armatures.new(name + "-rig"))
    bpy.context.scene.collection.objects.link(ob)
    bpy.context.scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    parent = None
    for k, head in enumerate(rig_heads()):
        bone = rig.data.edit_bones.new(f"bone{k}")
        bone.head, bone.tail = head.tolist(), (head + [0.0, 0.0, RIG_BONE_LENGTH]).tolist()
        if parent is not None:
            bone.parent, bone.use_connect = parent, True
        parent = bone
    bpy.ops.object.mode_set(mode="OBJECT")
    for k in range(RIG_BONES):
        ob.vertex_groups.new(name=f"bone{k}").add(np.flatnonzero(np.repeat(bone_of_box, 8) == k).tolist(), 1.0,
                                                 "REPLACE")
    ob.modifiers.new("Armature", "ARMATURE").object = rig
    for other in bpy.context.selected_objects:
        other.select_set(False)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    return ob, rig


def world_boxes(matrix, centres, sizes, rotations):
    """The boxes carried by a similarity ``matrix`` (4 x 4, Blender's matrix_world): centres
    moved, axes turned, sizes scaled by its one scale."""
    linear = matrix[:3, :3]
    scale = abs(np.linalg.det(linear)) ** (1 / 3)
    return centres @ linear.T + matrix[:3, 3], sizes * scale, np.einsum("ij,njk->nik", linear / scale, rotations)


TRANSFORM_CASES = ["mixamo", "mesh turned and scaled", "both, mirrored"]


def transformed_rig(bpy, case):
    """The rig of :func:`skinned_scene`, baked, then moved by the transforms of ``case`` (one of
    TRANSFORM_CASES). Returns (mesh object, armature object)."""
    ob, rig = skinned_scene(bpy)
    if case == "mixamo":  # armature at 0.01, turned and moved; the mesh its child at identity
        rig.scale = (0.01,) * 3
        rig.rotation_euler = (0.3, 0.2, 0.1)
        rig.location = (0.01, 0.02, 0.03)  # near the origin: float32 world positions stay exact to 1e-5
        ob.parent = rig
    elif case == "mesh turned and scaled":
        ob.rotation_euler = (0.0, 0.5, 0.2)
        ob.scale = (2.0,) * 3
        ob.location = (0.5, -1.0, 0.0)
    elif case == "both, mirrored":  # armature turned, mesh scaled by -1.5 (a mirror) under it
        rig.rotation_euler = (0.0, 0.0, 1.0)
        ob.parent = rig
        ob.scale = (-1.5, 1.5, 1.5)
    bpy.context.view_layer.update()
    return ob, rig


def unity_skinned_vertices(raw, skin):
    """What Unity's skinning hands a vertex program for a skinned FBX (tests/fbx_reader.py's
    geometry ``raw`` and ``skin``) posed by :func:`bone_motions`, per polygon corner, under the
    import rules docs/ENGINES.md (Skinning) cites: x negated for positions, normals, tangents and
    binormals; UVs as written; tangent.w from the side of the binormal; each bone's bind pose the
    inverse of its TransformLink times the mesh's bind transform (FBX stores Transform relative
    to the bone, so the mesh's is TransformLink x Transform); skinned vertex = sum of weight x
    posed bone x bind pose, normals and tangents by the same 3 x 3 parts. The posed bone: its
    TransformLink moved by the test's forward kinematics (in the file's axes). Returns
    (positions, normals, tangents (w = handedness), rest normals, rest tangents)."""
    if not UNITY["file_frame"]:
        raise NotModelled("Unity's Calculate normals or tangents (they would replace the box frame) are not modelled")
    mirror = np.diag([*UNITY["from_file"].diagonal(), 1.0])
    to_file = np.eye(4)
    to_file[:3, :3] = TO_Y_UP  # Blender world -> the file's axes (metres, Y-up, right-handed)
    matrices = np.zeros((len(raw["control_points"]), 4, 4))
    for k, motion in enumerate(bone_motions()):
        cluster = skin[f"bone{k}"]
        link = cluster["transform_link"]
        bind_pose = np.linalg.inv(link) @ (link @ cluster["transform"])
        posed_bone = to_file @ motion @ np.linalg.inv(to_file) @ link
        np.add.at(matrices, cluster["indexes"], cluster["weights"][:, None, None] * (mirror @ posed_bone @ bind_pose @ mirror))
    m = matrices[raw["vertex"]]
    normal, tangent, binormal = (raw[k] @ mirror[:3, :3].T for k in ("normal", "tangent", "binormal"))
    handedness = np.sign(np.einsum("ni,ni->n", np.cross(normal, tangent), binormal))[:, None]
    positions = np.einsum("nij,nj->ni", m[:, :3, :3], raw["position"] @ mirror[:3, :3].T) + m[:, :3, 3]
    return (positions, np.einsum("nij,nj->ni", m[:, :3, :3], normal),
            np.concatenate([np.einsum("nij,nj->ni", m[:, :3, :3], tangent), handedness], 1),
            normal, np.concatenate([tangent, handedness], 1))


def unity_skinned_decode(raw, skin):
    """The NORMAL_FRAME decode (origins, axes, half-extents per polygon corner) of what
    :func:`unity_skinned_vertices` hands the vertex program: with the skinned frame, and with
    the frame left at rest (the negative control)."""
    positions, normals, tangents, rest_normals, rest_tangents = unity_skinned_vertices(raw, skin)
    offset = np.concatenate([raw["BoxOffsetXY"], raw["BoxOffsetZIndex"][:, :1]], 1)
    half = np.concatenate([raw["BoxHalfXY"], raw["BoxHalfZ"][:, :1]], 1)
    return (decode_normal_frame(positions, normals, tangents, offset, half),
            decode_normal_frame(positions, rest_normals, rest_tangents, offset, half))


# Per-box shape ids of mixed_boxes() for the engines' per-box shape checks: box i draws the SDF
# preset MIXED_SHAPES[i] (bm_sdf_by_id), every preset but the box among them.
MIXED_SHAPES = np.array([5, 1, 6, 3, 4, 2, 1, 3, 5])


def paint_shapes(bpy, ob, shapes):
    """Paints ``shapes`` (one id per box, 8 vertices per box in order) as boxmarch_shape and
    bakes again (the geometry is unchanged: only the ids are written). Returns the baked boxes
    (origins, quaternions, half-extents; Blender object space) as core.boxes_from_bake reads them
    from the stored layers."""
    from boxmarch import core, mesh_io

    ob.data.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set("value", np.repeat(shapes, 8))
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    layers = mesh_io.read_baked_layers(ob.data)
    return core.boxes_from_bake(mesh_io.read_positions(ob.data), layers.shader_offsets(),
                                layers.vertex_quaternions(), np.repeat(np.arange(len(shapes)), 8))


def per_box_agreement(covered, shot, camera, boxes, shapes, **options):
    """Fraction of pixels where ``covered`` (an engine's (H, W) mask) equals the CPU reference
    drawing each of the Blender-space ``boxes`` with the preset its id in ``shapes`` picks
    (core.render_boxes_by_shape, with ``options``: e.g. preview_render.EXACT_MARCH), seen by the
    engine's camera (``shot.view`` and the harness's ``camera``: vertical fov in degrees, near,
    far) in the Y-up engine frame."""
    from boxmarch import core
    from tests.engines import perspective

    height, width = covered.shape
    to_world = np.eye(4)
    to_world[:3, :3] = TO_Y_UP
    to_clip = perspective(camera, width / height) @ shot.view @ to_world
    reference = core.render_boxes_by_shape(*boxes, shapes, to_clip, shot.view @ to_world, width, height, **options)
    return float((covered == reference.coverage).mean())

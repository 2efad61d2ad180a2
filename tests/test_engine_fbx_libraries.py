"""The UNITY and UNREAL FBX exports read by the FBX libraries engines use, beside the project's
own reader (tests/fbx_reader.py): ufbx (Godot 4.3+'s loader) in a child process, and Assimp 5.2
through its binary dump (tests/engines/fbx_libraries.py). Each library hands over the file's
numbers in the file's own axes and units; the engine's documented import rules
(engine_scene.UNITY, UNREAL: docs/ENGINES.md) and the documented decode then run on them, against
the generating boxes. The skinned rig (UNITY, NORMAL_FRAME) is posed by ufbx's own skinning: a
copy of the file with the bones' local transforms set to the pose of the test's forward
kinematics, which ufbx evaluates. Negative controls: the frame dropped (identity quaternion;
the rest frame under a pose) must fail.
"""
import numpy as np
import pytest

from tests.engine_scene import (TO_Y_UP, UNITY, UNREAL, baked_scene, bone_motions, box_of_vertex,
                                decode_normal_frame, decode_uv_frame, frame_and_size_errors, imported, posed_rig_boxes,
                                rig_boxes, skinned_scene)
from tests.engines import fbx_libraries
from tests.fbx_reader import read_fbx_geometry
from tests.helpers.tools import need

pytestmark = pytest.mark.slow

ENGINES = {"UNITY": UNITY, "UNREAL": UNREAL}
LIBRARIES = ("ufbx", "assimp")
# ufbx's CoordinateAxis codes of the file's declared axes: right +X, up +Y, front +Z (Y-up,
# right-handed: engine_scene.TO_Y_UP of Blender's axes), in metres.
FILE_AXES = [0, 2, 4]


def to_file():
    """4 x 4: Blender world -> the file's axes (what TO_Y_UP does to points)."""
    out = np.eye(4)
    out[:3, :3] = TO_Y_UP
    return out


def export_files(bpy, folder):
    """The mixed scene exported with UNITY and UNREAL, the skinned rig with UNITY, and (with ufbx)
    a posed copy of the rig: the bones at the forward kinematics' pose, placed from ufbx's rest
    reading. Leaves an empty scene."""
    from boxmarch.export import scene as export_scene

    bpy.ops.wm.read_factory_settings(use_empty=True)
    ob, centres, sizes, rotations = baked_scene(bpy)
    out = {"folder": folder, "scene": (centres, sizes, rotations)}
    for preset in ENGINES:
        out[preset] = folder / f"{preset}.fbx"
        export_scene.export_objects(bpy.context, [ob], preset, str(out[preset]))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rig_ob, _rig = skinned_scene(bpy)
    out["skinned"] = folder / "skinned.fbx"
    assert export_scene.export_objects(bpy.context, [rig_ob], "UNITY", str(out["skinned"]))["layout"] == "NORMAL_FRAME"
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if fbx_libraries.ufbx_available() is None:
        rest = fbx_libraries.read_with_ufbx(out["skinned"], folder)
        out["motions"] = {f"bone{k}": to_file() @ m @ np.linalg.inv(to_file()) for k, m in enumerate(bone_motions())}
        out["posed"] = folder / "posed.fbx"
        fbx_libraries.write_posed_copy(out["skinned"], out["posed"], posed_locals(rest, out["motions"]))
    return out


@pytest.fixture(scope="module")
def files(bpy_module, tmp_path_factory):
    return export_files(bpy_module, tmp_path_factory.mktemp("fbx_libraries"))


def posed_locals(rest, motions):
    """{bone: local transform} that puts each bone at motion x its rest world matrix (both as
    ufbx reads them) under its parent's posed world matrix."""
    out = {}
    for bone, motion in motions.items():
        parent = str(rest["parent:" + bone])
        parent_world = motions.get(parent, np.eye(4)) @ rest["world:" + parent]
        out[bone] = np.linalg.inv(parent_world) @ motion @ rest["world:" + bone]
    return out


def need_library(library):
    """Fails (not skips) when scripts/setup.sh's ``library`` is missing: these checks must run."""
    need((fbx_libraries.ufbx_available if library == "ufbx" else fbx_libraries.assimp_available)())


def library_read(library, path, folder):
    """{"position", UV map name...: per polygon corner, float64} as ``library`` delivers them
    (Assimp names no UV channel: they are named here by their order in the file)."""
    need_library(library)
    if library == "ufbx":
        data = fbx_libraries.read_with_ufbx(path, folder)
        assert list(data["axes"]) == FILE_AXES and data["unit_meters"] == 1.0  # ufbx keeps the file's frame
        out = {name: data["uv:" + name] for name in data["uv_names"]}
        out.update({k: data[k] for k in ("position", "normal", "tangent", "bitangent") if k in data})
        return out
    (mesh,) = fbx_libraries.read_with_assimp(path, folder)["meshes"]
    corners = np.concatenate(mesh["faces"])
    assert np.array_equal(corners, np.arange(len(corners)))  # one vertex per polygon corner, in file order
    names = read_fbx_geometry(path)["uv_maps"]
    assert len(mesh["uv"]) == len(names)
    out = dict(zip(names, mesh["uv"]))
    out.update({k: mesh[k] for k in ("position", "normal", "tangent", "bitangent") if k in mesh})
    return out


def same_numbers(library, delivered, ours):
    """The library hands over the file's numbers: ufbx as doubles, Assimp as float32 (its
    ai_real), so each of ours rounded to float32."""
    return np.array_equal(delivered, ours if library == "ufbx" else ours.astype(np.float32).astype(np.float64))


def static_errors(raw, engine, scene, frame=True):
    """(origin, axis, half-extent) errors of the UV_FRAME decode after ``engine``'s documented
    import, and the decoded indices; ``frame=False`` replaces the quaternion by the identity."""
    centres, sizes, rotations = scene
    positions, uvs = imported(raw, engine)
    if not frame:
        uvs[0], uvs[1] = np.zeros_like(uvs[0]), np.tile([0.0, 1.0], (len(uvs[1]), 1))
    box = box_of_vertex(positions, centres, sizes, rotations, engine["to_engine"])
    origins, axes, half, index = decode_uv_frame(positions, uvs)
    scale = engine["scale"]
    errors = frame_and_size_errors(origins, axes, half, box, centres * scale, sizes * scale, rotations,
                                   engine["to_engine"] / scale)
    return errors, index, box


@pytest.mark.parametrize("library", LIBRARIES)
@pytest.mark.parametrize("preset", sorted(ENGINES))
def test_library_reads_the_static_export_and_it_decodes(files, preset, library):
    """The mixed scene's UNITY and UNREAL exports (UV_FRAME): the library's positions and UV maps
    are the project's reader's numbers, and after the engine's documented import every corner
    decodes its box (origin, axes, half-extents, index); the identity quaternion does not."""
    raw = library_read(library, files[preset], files["folder"])
    ours = read_fbx_geometry(files[preset])
    for name in ["position"] + ours["uv_maps"]:  # the same numbers as the project's reader
        assert same_numbers(library, raw[name], ours[name]), name
    (origin, axis, half), index, box = static_errors(raw, ENGINES[preset], files["scene"])
    assert origin < 1e-5 and axis < 1e-6 and half < 1e-5, (origin, axis, half)
    assert np.array_equal(index, np.rint(index)) and sorted(set(index)) == list(range(len(files["scene"][0])))
    assert all(len(set(index[box == b])) == 1 for b in range(len(files["scene"][0])))
    # Negative control: the frame dropped (identity quaternion) misses the boxes.
    assert static_errors(raw, ENGINES[preset], files["scene"], frame=False)[0][0] > 0.1


def test_assimp_drops_the_by_vertex_normals_ufbx_and_ours_read(files):
    """Blender writes a static mesh's normals ByVertice + IndexToDirect (one per control point,
    through NormalsIndex). ufbx and tests/fbx_reader.py read them alike; Assimp 5.2 refuses the
    layer ("length of input data unexpected for ByVertice mapping", assimp/assimp#5116) and hands
    over no normals. The static layouts never read normals."""
    ufbx_raw, assimp_raw = (library_read(library, files["UNITY"], files["folder"]) for library in LIBRARIES)
    assert np.array_equal(ufbx_raw["normal"], read_fbx_geometry(files["UNITY"])["normal"])
    assert "normal" not in assimp_raw


def unity_decode(raw, position, normal, tangent):
    """NORMAL_FRAME decode (origins, axes, half-extents per corner) after Unity's documented
    import (docs/ENGINES.md, Skinning): x negated for positions, normals, tangents and binormals,
    tangent.w the side of the file's binormal. ``position``, ``normal``, ``tangent``: per corner
    in the file's axes, skinned or at rest; the rest of the corner's data comes from ``raw``."""
    mirror = UNITY["from_file"]
    rest_normal, rest_tangent, rest_binormal = (raw[k] @ mirror.T for k in ("normal", "tangent", "bitangent"))
    w = np.sign(np.einsum("ni,ni->n", np.cross(rest_normal, rest_tangent), rest_binormal))[:, None]
    offset = np.concatenate([raw["BoxOffsetXY"], raw["BoxOffsetZIndex"][:, :1]], 1)
    half = np.concatenate([raw["BoxHalfXY"], raw["BoxHalfZ"][:, :1]], 1)
    return decode_normal_frame(position @ mirror.T, normal @ mirror.T,
                               np.concatenate([tangent @ mirror.T, w], 1), offset, half)


def rig_box_of_corner(raw):
    centres, sizes, rotations, _bone_of_box = rig_boxes()
    return box_of_vertex(raw["position"] @ UNITY["from_file"].T, centres, sizes, rotations, UNITY["to_engine"])


def bone_weights(library, path, folder):
    """({bone: (indices, weights, bind matrix x rest world matrix)}, corner -> control point or
    None) as ``library`` delivers the skin: ufbx weighs the file's control points (the second
    item maps corners to them), Assimp its per-corner vertices; the matrix product is the
    identity when the library's bind pose and node hierarchy agree."""
    if library == "ufbx":
        data = fbx_libraries.read_with_ufbx(path, folder)
        return {str(b): (data["vertices:" + b], data["weights:" + b],
                         data["world:" + b] @ data["geometry_to_bone:" + b]) for b in data["cluster_bones"]}, data["vertex"]
    scene = fbx_libraries.read_with_assimp(path, folder)
    names = [node[0] for node in scene["nodes"]]
    world = {}
    for name, local, parent, _meshes in scene["nodes"]:
        world[name] = (world[names[parent]] if parent >= 0 else np.eye(4)) @ local
    (mesh,) = scene["meshes"]
    return {b: (vertices, weights, world[b] @ offset) for b, (offset, vertices, weights) in mesh["bones"].items()}, None


def rest_errors(raw, frame=True):
    """(origin, axis, half) errors of the rig's UNITY export decoded at rest after Unity's import;
    ``frame=False`` puts the identity frame in the normals and tangents (the negative control)."""
    centres, sizes, rotations, _bone_of_box = rig_boxes()
    normal, tangent = raw["normal"], raw["tangent"]
    if not frame:
        normal, tangent = np.tile([0.0, 0.0, 1.0], (len(normal), 1)), np.tile([1.0, 0.0, 0.0], (len(tangent), 1))
    return frame_and_size_errors(*unity_decode(raw, raw["position"], normal, tangent), rig_box_of_corner(raw),
                                 centres, sizes, rotations, UNITY["to_engine"])


@pytest.mark.parametrize("library", LIBRARIES)
def test_library_reads_the_skinned_export_at_rest(files, library):
    """The UNITY export of the rig: the library's corners equal the project's reader's, decode at
    the rest boxes (the identity frame does not), and each bone holds exactly its boxes' corners
    with weight 1 and a bind pose matching its rest place."""
    raw = library_read(library, files["skinned"], files["folder"])
    ours = read_fbx_geometry(files["skinned"])
    for name, our_name in [("position",) * 2, ("normal",) * 2, ("tangent",) * 2, ("bitangent", "binormal")] + [
            (n, n) for n in ours["uv_maps"]]:
        assert same_numbers(library, raw[name], ours[our_name]), name
    errors = rest_errors(raw)
    assert errors[0] < 1e-5 and errors[1] < 1e-6 and errors[2] < 1e-5, errors
    assert rest_errors(raw, frame=False)[0] > 0.1
    bone_of_corner = rig_boxes()[3][rig_box_of_corner(raw)]
    skin, corner_vertex = bone_weights(library, files["skinned"], files["folder"])
    assert sorted(skin) == ["bone0", "bone1", "bone2"]
    for k in range(3):
        indexes, weights, bind_times_rest = skin[f"bone{k}"]
        mine = np.flatnonzero(bone_of_corner == k)
        if corner_vertex is not None:
            mine = np.unique(corner_vertex[mine])
        assert sorted(indexes) == sorted(mine) and np.all(weights == 1.0)
        assert np.allclose(bind_times_rest, np.eye(4), atol=1e-6)


def posed_errors(rest_path, posed_path, folder, motions):
    """ufbx's skinning of the posed copy, decoded after Unity's import, against the posed boxes:
    ((origin, axis, half) errors, the same with the frame left at rest (the negative control)).
    Checks on the way that ufbx put each bone where the pose says and that the tangent's blend is
    ufbx's own (it reproduces ufbx's skinned positions)."""
    rest = fbx_libraries.read_with_ufbx(rest_path, folder)
    posed = fbx_libraries.read_with_ufbx(posed_path, folder)
    for bone, motion in motions.items():
        assert np.allclose(posed["world:" + bone], motion @ rest["world:" + bone], atol=1e-9), bone
    assert not posed["skinned_is_local"] and posed["skinned_generated_normals"]
    assert np.allclose(posed["skinned_blend_position"], posed["skinned_position"], rtol=0, atol=1e-12)
    assert np.abs(posed["skinned_position"] - rest["position"]).max() > 1.0  # the pose moved the mesh
    raw = {name: posed["uv:" + name] for name in posed["uv_names"]}
    raw.update({k: posed[k] for k in ("position", "normal", "tangent", "bitangent")})
    _centres, sizes, _rotations, _bone_of_box = rig_boxes()
    box = rig_box_of_corner(raw)
    posed_centres, posed_rotations = posed_rig_boxes()
    skinned = unity_decode(raw, posed["skinned_position"], posed["skinned_normal"], posed["skinned_tangent"])
    rest_frame = unity_decode(raw, posed["skinned_position"], raw["normal"], raw["tangent"])
    return tuple(frame_and_size_errors(*decoded, box, posed_centres, sizes, posed_rotations, UNITY["to_engine"])
                 for decoded in (skinned, rest_frame))


def test_ufbx_skinning_carries_each_box_to_its_posed_place(files):
    """ufbx's own skinning (evaluated at load) of the rig's UNITY export with the bones set to
    the test's forward-kinematics pose: each corner decodes at its box's posed place. Negative
    control: the frame left at rest (as UV channels would carry it) misses by far."""
    need_library("ufbx")
    errors, rest_frame = posed_errors(files["skinned"], files["posed"], files["folder"], files["motions"])
    assert errors[0] < 1e-5 and errors[1] < 1e-6 and errors[2] < 1e-5, errors
    assert rest_frame[0] > 0.1, rest_frame

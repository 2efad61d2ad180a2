"""Exports of turned, scaled and parented objects (issue 21, item 3): the box data must be in the
space the file writes the positions in. A skinned glTF holds world positions (its skin is the
identity at rest), so its frames, offsets and half-extents must be the world's; every other
file holds the object's own positions and leaves the transform to its node (glTF) or model
(FBX). Each file is read back (tests/gltf_reader.py, tests/fbx_reader.py), decoded with the
documented formulas (docs/ENGINES.md) and compared with the generating boxes carried by the
object's world matrix from Blender; a scale that shears boxes is refused, nothing written."""
import math
import pathlib

import numpy as np
import pytest

from tests.engine_scene import (TO_Y_UP, TRANSFORM_CASES, UNITY, baked_scene, box_of_vertex, decode_normal_frame,
                                decode_uv_frame, frame_and_size_errors, imported, rig_boxes, skinned_scene, table_texels,
                                transformed_rig, world_boxes)
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import node_globals, read_glb, read_skin
from tests.helpers.tools import need

TOLERANCES = (1e-5, 1e-6, 1e-5)  # origin / half-extent, axis, half-extent (float32 data)


def rest_skinning(path):
    """(primitive, positions, normals, tangents) of the file's skinned mesh at rest, skinned with
    the glTF 2.0 formula (joint matrix = the joint node's global transform x its inverse bind
    matrix, blended by WEIGHTS_0); normal and tangent through the same 3 x 3, made unit."""
    skin = read_skin(path)
    joints = np.array([skin["global"][j] @ ibm for j, ibm in zip(skin["joints"], skin["inverse_bind"])])
    (mesh,) = read_glb(path)
    (p,) = mesh["primitives"]
    blend = np.einsum("nk,nkij->nij", p["WEIGHTS_0"], joints[p["JOINTS_0"].astype(int)])
    turn = lambda v: np.einsum("nij,nj->ni", blend[:, :3, :3], v)
    unit = lambda v: v / np.linalg.norm(v, axis=1, keepdims=True)
    positions = turn(p["POSITION"]) + blend[:, :3, 3]
    tangents = np.concatenate([unit(turn(p["TANGENT"][:, :3])), p["TANGENT"][:, 3:]], 1)
    return p, positions, unit(turn(p["NORMAL"])), tangents


@pytest.mark.parametrize("case", TRANSFORM_CASES)
def test_skinned_gltf_decodes_the_world_boxes(blender, tmp_path, monkeypatch, case):
    from boxmarch.export import boxes, scene

    ob, _rig = transformed_rig(blender, case)
    matrix = np.array(ob.matrix_world)
    truth = world_boxes(matrix, *rig_boxes()[:3])
    path = tmp_path / "rig.glb"
    report = scene.export_objects(blender.context, [ob], "GLTF", str(path))
    assert report["meshes"][0]["space"] == "world" and report["transform_error"] < 1e-5, report
    p, positions, normals, tangents = rest_skinning(path)
    box = box_of_vertex(positions, *truth, TO_Y_UP)
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
    half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
    errors = frame_and_size_errors(*decode_normal_frame(positions, normals, tangents, offset, half), box, *truth,
                                   TO_Y_UP)
    assert all(e < t for e, t in zip(errors, TOLERANCES)), errors
    # Negative control: the box data in the mesh's own space (what a file holding object-space
    # box data beside world positions gives) misses the world boxes, and the report says so.
    monkeypatch.setattr(boxes, "written_space", lambda *_: None)
    wrong = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "wrong.glb"))
    p, positions, normals, tangents = rest_skinning(tmp_path / "wrong.glb")
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
    half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
    wrong_errors = frame_and_size_errors(*decode_normal_frame(positions, normals, tangents, offset, half), box,
                                         *truth, TO_Y_UP)
    assert wrong_errors[0] > 0.1 or wrong_errors[1] > 0.1, wrong_errors
    assert wrong["transform_error"] > 0.01 and any("decode up to" in w for w in wrong["warnings"]), wrong


def test_godot3_skinned_decodes_the_world_boxes(blender, tmp_path):
    """GODOT3 (NORMAL_COLOR): offsets in COLOR_0, half-extents in the .boxes.tres table by index."""
    from boxmarch.export import scene

    ob, _rig = transformed_rig(blender, "mixamo")
    truth = world_boxes(np.array(ob.matrix_world), *rig_boxes()[:3])
    path = tmp_path / "rig.glb"
    report = scene.export_objects(blender.context, [ob], "GODOT3", str(path))
    assert report["transform_error"] < 1e-5, report
    p, positions, normals, tangents = rest_skinning(path)
    table = table_texels((tmp_path / "rig.boxes.tres").read_text())
    colour = p["COLOR_0"]
    half = table[np.rint(colour[:, 3]).astype(int), :3]
    errors = frame_and_size_errors(*decode_normal_frame(positions, normals, tangents, colour[:, :3], half),
                                   box_of_vertex(positions, *truth, TO_Y_UP), *truth, TO_Y_UP)
    assert all(e < t for e, t in zip(errors, TOLERANCES)), errors


def test_unity_skinned_fbx_holds_the_mesh_in_its_own_space(blender, tmp_path):
    """FBX keeps a skinned mesh's vertices in the mesh's own space (its model and bind pose carry
    the transform), so the box data stays in that space: the file decodes the generating boxes
    in the object's coordinates (Unity's axes), whatever the object's transform."""
    from boxmarch.export import scene

    ob, _rig = transformed_rig(blender, "mesh turned and scaled")
    report = scene.export_objects(blender.context, [ob], "UNITY", str(tmp_path / "rig.fbx"))
    assert report["layout"] == "NORMAL_FRAME" and report["meshes"][0]["space"] == "object"
    raw = read_fbx_geometry(tmp_path / "rig.fbx")
    centres, sizes, rotations, _bones = rig_boxes()
    mirror = UNITY["from_file"]
    positions = raw["position"] @ mirror.T
    normal, tangent, binormal = (raw[k] @ mirror.T for k in ("normal", "tangent", "binormal"))
    handedness = np.sign(np.einsum("ni,ni->n", np.cross(normal, tangent), binormal))[:, None]
    offset = np.concatenate([raw["BoxOffsetXY"], raw["BoxOffsetZIndex"][:, :1]], 1)
    half = np.concatenate([raw["BoxHalfXY"], raw["BoxHalfZ"][:, :1]], 1)
    decoded = decode_normal_frame(positions, normal, np.concatenate([tangent, handedness], 1), offset, half)
    box = box_of_vertex(positions, centres, sizes, rotations, UNITY["to_engine"])
    errors = frame_and_size_errors(*decoded, box, centres, sizes, rotations, UNITY["to_engine"])
    assert all(e < t for e, t in zip(errors, TOLERANCES)), errors


def static_object(blender):
    """The mixed boxes (engine_scene.baked_scene), parented to a turned, moved empty and given
    a non-uniform scale: fine for a static export, whose node carries it."""
    ob, centres, sizes, rotations = baked_scene(blender)
    empty = blender.data.objects.new("Holder", None)
    blender.context.scene.collection.objects.link(empty)
    empty.rotation_euler, empty.location, empty.scale = (0.4, -0.3, 1.1), (2.0, 0.0, -1.0), (1.5, 1.5, 1.5)
    ob.parent = empty
    ob.rotation_euler, ob.scale = (0.0, 0.7, 0.0), (1.0, 2.0, 0.5)
    blender.context.view_layer.update()
    return ob, centres, sizes, rotations


def test_static_gltf_of_a_parented_non_uniformly_scaled_object(blender, tmp_path):
    """The node holds the object's world transform, the mesh its own coordinates: decoded in the
    mesh's space and carried by the node's global matrix, every vertex lands on its box's world
    centre (an affine map keeps centres; the shader marches in the object's space, where the box
    is still a box)."""
    from boxmarch.export import scene

    ob, centres, sizes, rotations = static_object(blender)
    path = tmp_path / "static.glb"
    report = scene.export_objects(blender.context, [ob], "GLTF", str(path))
    assert report["meshes"][0]["space"] == "object" and report["transform_error"] < 1e-5
    from tests.gltf_reader import chunks, node_matrix

    doc, _ = chunks(path.read_bytes())
    parent = np.full(len(doc["nodes"]), -1)
    for i, node in enumerate(doc["nodes"]):
        for c in node.get("children", []):
            parent[c] = i
    globals_ = node_globals(np.array([node_matrix(n) for n in doc["nodes"]]), parent)
    (node,) = [i for i, n in enumerate(doc["nodes"]) if "mesh" in n]
    (mesh,) = read_glb(path)
    (p,) = mesh["primitives"]
    box = box_of_vertex(p["POSITION"], centres, sizes, rotations, TO_Y_UP)
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
    half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
    local = decode_normal_frame(p["POSITION"], p["NORMAL"], p["TANGENT"], offset, half)
    assert all(e < t for e, t in zip(frame_and_size_errors(*local, box, centres, sizes, rotations, TO_Y_UP),
                                     TOLERANCES))
    world = local[0] @ globals_[node][:3, :3].T + globals_[node][:3, 3]
    matrix = np.array(ob.matrix_world)
    true_world = (centres[box] @ matrix[:3, :3].T + matrix[:3, 3]) @ TO_Y_UP.T
    reach = np.abs(matrix[:3, :3]).max() * sizes[box].max(axis=1) / 2
    assert (np.linalg.norm(world - true_world, axis=1) / reach).max() < 1e-5


@pytest.mark.parametrize("preset", ["UNITY", "UNREAL"])
def test_static_fbx_of_a_parented_non_uniformly_scaled_object(blender, tmp_path, preset):
    """FBX writes the object's own coordinates (its model carries the transform): the UV_FRAME
    decode of the file, through the modelled importer, lands on the generating boxes in the
    object's space whatever the object's transform."""
    from boxmarch.export import scene
    from tests.engine_scene import UNREAL

    engine = {"UNITY": UNITY, "UNREAL": UNREAL}[preset]
    ob, centres, sizes, rotations = static_object(blender)
    path = tmp_path / "static.fbx"
    report = scene.export_objects(blender.context, [ob], preset, str(path))
    assert report["meshes"][0]["space"] == "object"
    positions, uvs = imported(read_fbx_geometry(path), engine)
    origins, axes, half, _index = decode_uv_frame(positions, uvs)
    scale = engine["scale"]
    box = box_of_vertex(positions, centres, sizes, rotations, engine["to_engine"])
    errors = frame_and_size_errors(origins / scale, axes, half / scale, box, centres, sizes, rotations,
                                   engine["to_engine"] / scale)
    assert all(e < t for e, t in zip(errors, TOLERANCES)), errors


@pytest.mark.parametrize("what", ["mesh", "armature"])
def test_a_scale_that_shears_skinned_boxes_is_refused(blender, tmp_path, what):
    """A non-uniform scale across a turned box's axes makes it a parallelepiped in the world
    space a skinned glTF holds: no frame decodes it, so the export refuses, names the object and
    writes nothing (no file, no partial file, the scene as it was)."""
    from boxmarch.export import scene

    ob, rig = skinned_scene(blender)
    if what == "mesh":
        ob.scale = (1.0, 1.0, 3.0)
    else:
        ob.parent = rig
        rig.scale = (2.0, 1.0, 1.0)
    blender.context.view_layer.update()
    names = sorted(m.name for m in blender.data.meshes)
    with pytest.raises(scene.ExportInputError, match=r"object 'Skinned': its world transform scales 36 of its 36 "
                                                     r"boxes unevenly .*apply the scale"):
        scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "sheared.glb"))
    assert list(tmp_path.iterdir()) == []
    assert sorted(m.name for m in blender.data.meshes) == names and rig.data.pose_position == "POSE"
    # The same object exports as a static mesh (its node carries the scale) with the UNREAL-free
    # FBX of Unity too: only the world-space file is refused.
    ob.modifiers.clear()
    assert scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "static.glb"))["transform_error"] < 1e-5


def test_frames_in_space_keeps_boxes_an_axis_scale_does_not_shear():
    """Blender-free: axis-aligned boxes under diag(1, 2, 3) stay boxes with half-extents scaled per
    axis; the same boxes turned 30 degrees about z are sheared; a mirror keeps the decode exact."""
    from boxmarch.formats import transforms

    rng = np.random.default_rng(3)
    f = rng.normal(size=(4, 3))
    half = np.array([[1.0, 2.0, 3.0], [0.5, 0.5, 0.5]])
    box = np.array([0, 0, 1, 1])
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (4, 1))
    q, f2, h2, sheared = transforms.frames_in_space(identity, f, half, box, np.diag([1.0, 2.0, 3.0]))
    assert sheared == 0 and np.allclose(h2, half * [1, 2, 3]) and np.allclose(f2, f * [1, 2, 3])
    assert np.allclose(np.abs(q[:, 3]), 1.0)
    turn = np.tile([0.0, 0.0, math.sin(math.pi / 12), math.cos(math.pi / 12)], (4, 1))
    assert transforms.frames_in_space(turn, f, half, box, np.diag([1.0, 2.0, 3.0]))[3] == 2
    mirror = np.diag([-2.0, 2.0, 2.0])
    q, f2, h2, sheared = transforms.frames_in_space(turn, f, half, box, mirror)
    from boxmarch import core

    assert sheared == 0 and np.allclose(h2, 2 * half)
    assert np.allclose(core.rotate_vector(f2, q), core.rotate_vector(f, turn) @ mirror.T)


RENDER_W, RENDER_H = 400, 300


def engine_camera(centres_engine):
    """A camera 4.6 units from the middle of the boxes (engine frame), from the side."""
    target = centres_engine.mean(axis=0)
    return {"position": (target + [4.0, 1.25, -2.0]).tolist(), "target": target.tolist(), "fov": 50,
            "near": 0.5, "far": 40}


@pytest.mark.slow
def test_engines_draw_a_turned_and_scaled_rig_where_its_boxes_are(blender, tmp_path, monkeypatch):
    """The rig with its armature at scale 0.5, turned and moved (the mesh its child), exported
    with GLTF and GODOT3 and drawn at rest by three.js r111 and Godot 3.2 with the shipped
    shaders raymarching a box at 0.6 of each half-extent: the pixels cover the world boxes'
    silhouettes within 1 px. Negative control: the box data left in the mesh's own space (the
    mesh's half-extents, twice the world's) fails in both."""
    from boxmarch.export import boxes, scene
    from boxmarch.formats import shader_sources
    from tests.engine_scene import silhouettes
    from tests.engines import coverage_mismatch, godot3, threejs
    from tests.test_engine_skinned import godot3_import_skinned, setup_js

    ob, rig = skinned_scene(blender)
    rig.scale, rig.rotation_euler, rig.location = (0.5,) * 3, (0.3, 0.2, 0.8), (0.5, -0.5, 0.2)
    ob.parent = rig
    blender.context.view_layer.update()
    centres, sizes, rotations = world_boxes(np.array(ob.matrix_world), *rig_boxes()[:3])
    camera = engine_camera(centres @ TO_Y_UP.T)
    material = (shader_sources.shader_dir() / "threejs" / "boxmarch.js").read_text()
    need(threejs.available())
    need(godot3.available())

    def draws(folder):
        folder.mkdir()
        scene.export_objects(blender.context, [ob], "GLTF", str(folder / "rig.glb"))
        shot = threejs.render((folder / "rig.glb").read_bytes(), material, setup_js(angle=0.0), RENDER_W, RENDER_H,
                              camera)
        covered = shot.pixels[..., 3] > 0
        results = [(covered, silhouettes(shot, centres, 0.6 * sizes, rotations, TO_Y_UP))]
        project = godot3_import_skinned(blender.context, ob, folder)
        shot = godot3.render(project, godot3.shipped_shader("return sd_box(p, 0.6 * h);"), width=RENDER_W,
                             height=RENDER_H, camera=camera,
                             uniforms={"box_table": "res://model.boxes.tres", "max_steps": 256})
        covered = shot.pixels[..., :3].max(axis=2) > 20
        results.append((covered, silhouettes(shot, centres, 0.6 * sizes, rotations, TO_Y_UP)))
        return results

    for covered, expected in draws(tmp_path / "world"):
        assert covered.sum() > 1500
        mismatch = coverage_mismatch(covered, expected)
        assert mismatch is None, mismatch
    monkeypatch.setattr(boxes, "written_space", lambda *_: None)
    for covered, expected in draws(tmp_path / "object"):
        assert covered.sum() > 1500  # it drew, in the wrong places
        assert coverage_mismatch(covered, expected) is not None


def test_skinned_objects_sharing_a_mesh_in_different_places_are_refused(blender, tmp_path):
    """Two skinned objects on one mesh, one moved: a skinned glTF holds each in world space, so
    one set of box data cannot serve both; refused, nothing written. Unmoved, they export."""
    from boxmarch.export import scene

    ob, _rig = skinned_scene(blender)
    twin = ob.copy()  # a linked duplicate: same mesh, same modifier
    blender.context.scene.collection.objects.link(twin)
    blender.context.view_layer.update()
    report = scene.export_objects(blender.context, [ob, twin], "GLTF", str(tmp_path / "same.glb"))
    assert report["transform_error"] < 1e-5
    twin.location = (3.0, 0.0, 0.0)
    blender.context.view_layer.update()
    with pytest.raises(scene.ExportInputError, match="share the mesh 'Skinned' .* Make Single User"):
        scene.export_objects(blender.context, [ob, twin], "GLTF", str(tmp_path / "moved.glb"))
    assert not (tmp_path / "moved.glb").exists()


@pytest.mark.slow
def test_skinned_gltf_from_blender_34_decodes_the_world_boxes(package_parent, tmp_path):
    """Debian's Blender 3.4 (its own glTF exporter): the same transformed rigs, exported in the
    program, decode the world boxes read back here."""
    import json

    from tests.helpers.blender_program import SCRIPTS, run_blender

    run_blender(["--background", "--factory-startup", "--python-exit-code", "1", "--python",
                 str(SCRIPTS / "export_space_check.py"), "--", str(package_parent),
                 str(pathlib.Path(__file__).parent.parent), str(tmp_path)], tmp_path)
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["version"][:2] == [3, 4]
    for case in TRANSFORM_CASES:
        figures = result["cases"][case]
        assert figures["space"] == "world" and figures["transform_error"] < 1e-5, (case, figures)
        truth = world_boxes(np.array(figures["matrix_world"]), *rig_boxes()[:3])
        p, positions, normals, tangents = rest_skinning(tmp_path / f"{case}.glb")
        offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
        half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
        errors = frame_and_size_errors(*decode_normal_frame(positions, normals, tangents, offset, half),
                                       box_of_vertex(positions, *truth, TO_Y_UP), *truth, TO_Y_UP)
        assert all(e < t for e, t in zip(errors, TOLERANCES)), (case, errors)

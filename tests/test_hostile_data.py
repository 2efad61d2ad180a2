"""Hostile inputs, round 2 (issue 21; docs/CHECKS.md lists them): data the rebuild tools must not
lose, shape keys the bake cannot see, geometry edited after the bake. Each case gets a clear
message or warning, and a refusal changes nothing."""
import numpy as np
import pytest

from boxmarch import mesh_io, scenes
from tests.conftest import mesh_object
from tests.engine_scene import decode_normal_frame
from tests.gltf_reader import read_glb
from tests.test_tools_blender import faces_object, split_boxes


def baked_boxes(bpy, name="Boxes", count=6, encoding="FLOAT_COLOR"):
    """A baked object of ``count`` random boxes (8 vertices each, in order)."""
    arrays, *_ = scenes.random_boxes(count, seed=11, spread=6.0, size_range=(0.5, 1.5))
    ob = mesh_object(bpy, name, *arrays)
    assert bpy.ops.boxmarch.bake(encoding=encoding) == {"FINISHED"}
    return ob


def set_positions(mesh, positions):
    mesh.vertices.foreach_set("co", np.ascontiguousarray(positions, np.float32).reshape(-1))
    mesh.update()


# --- 7: shape keys the bake and the export read past ---------------------------------------------

def shape_keyed(bpy):
    ob = baked_boxes(bpy)
    ob.shape_key_add(name="Basis")
    key = ob.shape_key_add(name="Taller", from_mix=False)
    key.data.foreach_set("co", (mesh_io.read_positions(ob.data) * [1, 1, 2]).reshape(-1))
    key.value = 0.0
    return ob, key


def test_a_shown_shape_key_is_warned_about_in_bake_and_export(blender, tmp_path, capfd):
    from boxmarch.export import scene

    ob, key = shape_keyed(blender)
    assert mesh_io.modifier_warnings([ob]) == []  # a key at value 0 changes nothing shown
    # ... but the file carries it: a morph in the engine moves vertices, not the boxes.
    report = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "morph.glb"))
    assert [w for w in report["warnings"] if "shape key" in w] == [
        "object 'Boxes' has shape keys ('Taller'): the file carries them as morph targets, which move vertices but "
        "not the baked boxes: a morph that moves a box's vertices unevenly makes it decode off"]
    key.value = 0.7
    (warning,) = mesh_io.modifier_warnings([ob])
    assert "object 'Boxes' shows shape key 'Taller': the bake uses the mesh without them" in warning
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    assert "shows shape key 'Taller'" in capfd.readouterr().out  # the operator's WARNING report
    report = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "keyed.glb"))
    assert any("object 'Boxes' shows shape key 'Taller': the export uses" in w for w in report["warnings"])
    assert blender.ops.boxmarch.preview_toggle() == {"FINISHED"}
    assert "shows shape key 'Taller': the preview uses" in capfd.readouterr().out
    assert blender.ops.boxmarch.preview_toggle() == {"FINISHED"}  # off again
    # Muted, it is not shown; pinned (Shape Key Lock) with the active key, it is, whatever its value.
    key.mute = True
    assert mesh_io.modifier_warnings([ob]) == []
    key.mute, key.value = False, 0.0
    ob.show_only_shape_key, ob.active_shape_key_index = True, 1
    assert "shows shape key 'Taller'" in mesh_io.modifier_warnings([ob])[0]
    ob.active_shape_key_index = 0  # the reference pinned: the mesh data itself
    assert mesh_io.modifier_warnings([ob]) == []


# --- 5: export after the geometry changed since the bake ---------------------------------------

def test_export_after_an_edit_warns_and_counts_the_stale_boxes(blender, tmp_path):
    """Box 0 stretched by 2 units along x after the bake: its stored offsets now decode up to 2
    units away from the vertices' common origin. The export still writes the file (as Blender's
    exporters do with stale data) but names the object and the stale box count in a warning and
    in the report; moving a whole box keeps it decoding and is not counted."""
    from boxmarch.export import scene

    ob = baked_boxes(blender)
    positions = mesh_io.read_positions(ob.data).astype(np.float64)
    fresh = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "fresh.glb"))
    assert fresh["stale_boxes"] == 0 and not any("since the bake" in w for w in fresh["warnings"])

    moved = positions.copy()
    moved[8:16] += [3.0, -1.0, 0.5]  # box 1 moved whole: still decodes
    box0 = moved[:8]
    far = box0[:, 0] > box0[:, 0].mean()
    box0[far, 0] += 2.0  # box 0 stretched
    set_positions(ob.data, moved)
    report = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "stale.glb"))
    assert report["stale_boxes"] == 1 and report["meshes"][0]["stale_boxes"] == 1
    assert any("object 'Boxes': 1 of 6 boxes changed shape since the bake" in w and "Bake Box Frames again" in w
               for w in report["warnings"])
    # What the warning is about: the file's box 0 decodes off by the stretch.
    (mesh,) = read_glb(tmp_path / "stale.glb")
    p = mesh["primitives"][0]
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], 1)
    origins, _axes, _half = decode_normal_frame(p["POSITION"], p["NORMAL"], p["TANGENT"], offset, None)
    index = np.rint(p["TEXCOORD_2"][:, 1]).astype(int)
    spread = np.ptp(origins[index == 0], axis=0).max()
    assert spread > 1.9, spread
    assert np.ptp(origins[index == 1], axis=0).max() < 1e-5

    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    again = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "again.glb"))
    assert again["stale_boxes"] == 0


def test_an_8_bit_bake_is_not_taken_for_stale(blender, tmp_path):
    from boxmarch.export import scene

    ob = baked_boxes(blender, count=40, encoding="BYTE_COLOR")
    report = scene.export_objects(blender.context, [ob], "UNITY", str(tmp_path / "byte.fbx"), layout="CLASSIC")
    assert report["stale_boxes"] == 0


# --- 2: the rebuilding tools keep what a mesh holds outside its generic attributes --------------

def skin_radii(mesh):
    radii = np.empty(len(mesh.vertices) * 2, np.float32)
    mesh.skin_vertices[0].data.foreach_get("radius", radii)
    return radii.reshape(-1, 2)


def run_on_all(bpy, ob, operator, **options):
    bpy.ops.object.mode_set(mode="OBJECT")
    for other in bpy.context.scene.objects:
        other.select_set(other == ob)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    assert getattr(bpy.ops.boxmarch, operator)(**options) == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")


@pytest.mark.parametrize("operator, options", [("dedup_submeshes", {"tolerance": 1e-4}),
                                               ("merge_by_distance_submeshes", {"distance": 1e-3})])
def test_skin_radii_survive_the_rebuilding_tools(blender, operator, options):
    """A Skin modifier's radii live in the mesh's skin layer, not in a generic attribute: the tools
    keep them (Blender's own delete and merge carry every layer), each vertex that stays with its
    own radii (merged: those of one of the vertices merged into it)."""
    if operator == "dedup_submeshes":  # 5 boxes, each with a copy 1e-5 away
        arrays, *_ = scenes.random_boxes(5, seed=2, spread=8.0)
        n = len(arrays[0])
        arrays = (np.concatenate([arrays[0], arrays[0] + np.float32(1e-5)]),
                  np.concatenate([arrays[1], arrays[1] + n]), np.concatenate([arrays[2], arrays[2] + len(arrays[4])]),
                  np.concatenate([arrays[3], arrays[3]]), np.concatenate([arrays[4], arrays[4] + n]))
        ob = mesh_object(blender, "Skinned", *arrays)
        kept_vertices = n
    else:  # 4 boxes of 12 vertices, 4 of them doubles 1e-4 from a corner: 8 each after the merge
        positions, starts, sizes, corners = split_boxes(np.arange(4)[:, None] * np.array([2.0, 0, 0]), 1e-4)
        ob = faces_object(blender, "Skinned", positions, starts, sizes, corners)
        kept_vertices = 32
    before = mesh_io.read_positions(ob.data)
    ob.modifiers.new("Skin", "SKIN")
    radii = np.random.default_rng(4).uniform(0.1, 0.9, (len(before), 2)).astype(np.float32)
    ob.data.skin_vertices[0].data.foreach_set("radius", radii.reshape(-1))
    run_on_all(blender, ob, operator, **options)
    mesh = ob.data
    assert len(mesh.vertices) == kept_vertices
    assert len(mesh.skin_vertices) == 1, "the skin layer was dropped"
    after, kept = mesh_io.read_positions(mesh), skin_radii(mesh)
    for position, radius in zip(after, kept):
        near = np.linalg.norm(before - position, axis=1) <= 2e-3
        assert (radii[near] == radius).all(axis=1).any(), (position, radius)


def corner_normal_table(bpy, ob):
    """(corners, 6) array: each corner's position and its normal."""
    mesh = ob.data
    positions = mesh_io.read_positions(mesh)
    normals = np.empty(len(mesh.loops) * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", normals)
    return np.concatenate([positions[mesh_io.read_topology(mesh)[3]], normals.reshape(-1, 3)], axis=1)


def same_corner_normals(a, b, tolerance=2e-3) -> bool:
    """Whether the corners of ``a`` and ``b`` pair one to one, each at the same position with
    normals within ``tolerance`` (Blender stores custom normals as 16-bit integers: releases
    round them differently, so equal rounding to a grid would flip on a boundary)."""
    unused = list(range(len(b)))
    for row in a:
        match = next((j for j in unused if np.abs(b[j] - row).max() <= tolerance), None)
        if match is None:
            return False
        unused.remove(match)
    return not unused


def test_merge_keeps_custom_normals_as_blenders_merge_does(blender):
    """Custom normals are stored relative to each vertex's fan of corners, which a weld changes:
    the merge leaves them as Blender's own Merge by Distance does (a rebuild copying the stored
    values would turn them)."""
    tables = []
    for tool in (True, False):
        blender.ops.wm.read_factory_settings(use_empty=True)
        positions, starts, sizes, corners = split_boxes(np.arange(2)[:, None] * np.array([2.0, 0, 0]), 1e-4)
        ob = faces_object(blender, "Normals", positions, starts, sizes, corners)
        normals = np.random.default_rng(1).normal(size=(len(positions), 3))
        ob.data.normals_split_custom_set_from_vertices((normals / np.linalg.norm(normals, axis=1)[:, None]).tolist())
        if tool:
            run_on_all(blender, ob, "merge_by_distance_submeshes", distance=1e-3)
        else:
            blender.ops.object.mode_set(mode="EDIT")
            blender.ops.mesh.select_all(action="SELECT")
            blender.ops.mesh.remove_doubles(threshold=1e-3)
            blender.ops.object.mode_set(mode="OBJECT")
        assert len(ob.data.vertices) == 16 and ob.data.has_custom_normals
        tables.append(corner_normal_table(blender, ob))
    assert same_corner_normals(*tables)
    # Negative control: one corner's normal turned is found.
    turned = tables[1].copy()
    turned[0, 3:] = -turned[0, 3:]
    assert not same_corner_normals(tables[0], turned)

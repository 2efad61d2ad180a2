"""Hostile inputs through the add-on and the command line (issue 14; docs/CHECKS.md lists them):
no crash, no data loss, nothing silently wrong, one clear message."""
import os

import numpy as np
import pytest

from boxmarch import core, mesh_io, scenes
from tests.conftest import digest, random_boxes_object
from tests.helpers.blender_program import run_module


def boxes(bpy, name="Boxes", count=4, offset=0.0, select=True):
    return random_boxes_object(bpy, name, count, offset, select)


def worst_decode_error(bpy, ob):
    """Worst distance between a vertex's decode and its submesh's bounds centre, over the half-extent."""
    mesh = ob.data
    layers = mesh_io.read_baked_layers(mesh)
    offsets = layers.shader_offsets()
    q = np.zeros((len(mesh.vertices), 4), np.float32)
    q[layers.corner_verts] = np.concatenate([layers.quat_xy, layers.quat_zw], 1)
    positions = mesh_io.read_positions(mesh).astype(np.float64)
    origins = positions + core.rotate_vector(core.decode_offsets(offsets), q)
    sub, count = core.find_submeshes(positions.astype(np.float32), *mesh_io.read_topology(mesh))
    worst = 0.0
    for s in range(count):
        o = origins[sub == s]
        worst = max(worst, float(np.abs(o - o.mean(0)).max() / (np.ptp(positions[sub == s], 0).max() / 2)))
    return worst


def test_stale_layers_do_not_survive_skip_unchanged(blender):
    bpy = blender
    ob = boxes(bpy)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert worst_decode_error(bpy, ob) < 1e-5
    # An artist unwraps with BoxQuatXY active: the stored quaternion is overwritten.
    corners = len(ob.data.loops)
    mesh_io.write_uv(ob.data, mesh_io.QUAT_XY_UV, np.random.default_rng(0).random((corners, 2)).astype(np.float32))
    assert worst_decode_error(bpy, ob) > 0.1
    prepared = mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings())
    assert prepared.result.baked == prepared.result.submesh_count  # nothing skipped as "unchanged"
    prepared.write()
    assert worst_decode_error(bpy, ob) < 1e-5
    # Untouched since: now the skip is right.
    again = mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings())
    assert again.result.baked == 0 and again.result.unchanged == again.result.submesh_count


def test_modifiers_are_warned_about_in_bake_and_export(blender, tmp_path):
    bpy = blender
    ob = boxes(bpy)
    ob.modifiers.new("Mirror", "MIRROR")
    warnings = mesh_io.modifier_warnings([ob])
    assert len(warnings) == 1
    assert "modifiers that move vertices (Mirror): the bake uses the base mesh" in warnings[0]
    arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    bpy.context.scene.collection.objects.link(arm)
    ob.modifiers.new("Armature", "ARMATURE").object = arm
    warnings = mesh_io.modifier_warnings([ob])
    assert any("Armature modifier (Armature): the bake uses the rest geometry" in w for w in warnings)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}  # baked, with a WARNING report
    from boxmarch.export import scene

    report = scene.export_objects(bpy.context, [ob], "GLTF", str(tmp_path / "m.glb"))
    assert any("the export uses the base mesh" in w for w in report["warnings"])


def test_a_posed_rig_is_baked_at_rest_and_the_bake_says_so(blender, capfd):
    """The bake reads the mesh data, the rest geometry, whatever the pose: the baked offsets
    decode onto the rig's rest boxes (engine_scene.rig_boxes), not the posed ones."""
    import mathutils

    from tests.engine_scene import rig_boxes, skinned_scene

    bpy = blender
    ob, rig = skinned_scene(bpy)
    rig.pose.bones["bone1"].rotation_quaternion = mathutils.Quaternion((1.0, 0.0, 0.0), 0.7)
    bpy.context.view_layer.update()
    posed = mesh_io.read_positions(ob.evaluated_get(bpy.context.evaluated_depsgraph_get()).data)
    assert np.abs(posed - mesh_io.read_positions(ob.data)).max() > 0.5  # the pose moves the shown mesh
    capfd.readouterr()
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert "Armature modifier (Armature): the bake uses the rest geometry" in capfd.readouterr().out
    layers = mesh_io.read_baked_layers(ob.data)
    positions = mesh_io.read_positions(ob.data).astype(np.float64)
    origins = positions + core.rotate_vector(core.decode_offsets(layers.shader_offsets()), layers.vertex_quaternions())
    centres, sizes, _rotations, _bones = rig_boxes()
    rest_centre = np.repeat(centres, 8, axis=0)  # scenes.box_arrays: 8 vertices per box, in order
    assert (np.linalg.norm(origins - rest_centre, axis=1) / np.repeat(sizes.max(axis=1) / 2, 8)).max() < 1e-5


def scene_state(bpy):
    return ([(ob.name, ob.select_get(), ob.data.name if ob.data else None) for ob in bpy.context.scene.objects],
            sorted(m.name for m in bpy.data.meshes), bpy.context.view_layer.objects.active.name)


@pytest.mark.parametrize("preset, layout, change, message", [
    ("GLTF", "UV_FRAME", None, "the UV_FRAME layout keeps the box frame in UV maps.*export with the NORMAL_FRAME"),
    ("GLTF", "CLASSIC", None, "the CLASSIC layout keeps the box frame in UV maps"),
    ("UNITY", "UV_FRAME", None, "export with the NORMAL_FRAME layout"),
    ("GLTF", None, "envelopes", "deforms by bone envelopes: engine skins carry vertex-group weights only"),
    ("GLTF", None, "two modifiers", "2 Armature modifiers .*: an engine skin follows one armature"),
    ("GLTF", None, "rig outside the view layer", "which is not in the view layer"),
], ids=["gltf-uv-frame", "gltf-classic", "unity-uv-frame", "envelopes", "two-modifiers", "rig-unlinked"])
def test_skinned_exports_that_cannot_work_are_refused_and_write_nothing(blender, tmp_path, preset, layout, change,
                                                                         message):
    from boxmarch.export import scene

    from tests.engine_scene import skinned_scene

    bpy = blender
    ob, rig = skinned_scene(bpy)
    if change == "envelopes":
        ob.modifiers["Armature"].use_bone_envelopes = True
    elif change == "two modifiers":
        ob.modifiers.new("Armature.001", "ARMATURE").object = rig
    elif change == "rig outside the view layer":
        bpy.context.scene.collection.objects.unlink(rig)
    before = scene_state(bpy)
    path = tmp_path / f"skinned{'.fbx' if preset == 'UNITY' else '.glb'}"
    with pytest.raises(scene.ExportInputError, match=message):
        scene.export_objects(bpy.context, [ob], preset, str(path), layout)
    assert list(tmp_path.iterdir()) == []
    assert scene_state(bpy) == before and rig.data.pose_position == "POSE"


def test_export_of_the_same_object_twice_exports_it_once(blender, tmp_path):
    bpy = blender
    ob = boxes(bpy, "Baked")
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    from boxmarch.export import scene

    report = scene.export_objects(bpy.context, [ob, ob], "GLTF", str(tmp_path / "twice.glb"))
    assert report["objects"] == ["Baked"]
    assert bpy.data.objects.get("Baked") is not None and ob.data.users == 1
    assert ob.name in bpy.context.scene.objects


def test_multi_object_edit_mode_bakes_what_is_selected(blender):
    bpy = blender
    a = boxes(bpy, "A")
    b = boxes(bpy, "B", offset=20.0)
    bpy.context.view_layer.objects.active = a
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    for items in (b.data.vertices, b.data.edges, b.data.polygons):
        items.foreach_set("select", np.zeros(len(items), bool))
    bpy.ops.object.mode_set(mode="EDIT")
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    bpy.ops.object.mode_set(mode="OBJECT")
    assert a.data.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE) is not None
    assert b.data.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE) is None  # left alone


def test_a_non_colour_boxoffset_attribute_is_not_replaced(blender):
    bpy = blender
    ob = boxes(bpy)
    ob.data.attributes.new(mesh_io.OFFSET_ATTRIBUTE, "FLOAT_VECTOR", "POINT")
    with pytest.raises(RuntimeError, match="not a colour"):
        bpy.ops.boxmarch.bake()
    assert ob.data.attributes[mesh_io.OFFSET_ATTRIBUTE].data_type == "FLOAT_VECTOR"


def test_instance_on_curve_refuses_a_spacing_that_would_create_millions(blender):
    bpy = blender
    curve_data = bpy.data.curves.new("Path", "CURVE")
    spline = curve_data.splines.new("POLY")
    spline.points.add(1)
    spline.points[0].co = (0, 0, 0, 1)
    spline.points[1].co = (10, 0, 0, 1)
    curve = bpy.data.objects.new("Path", curve_data)
    bpy.context.scene.collection.objects.link(curve)
    cube = boxes(bpy, "Link", count=1, select=False)
    bpy.context.view_layer.objects.active = curve
    curve.select_set(True)
    with pytest.raises(RuntimeError, match="would create 10,000,001 copies"):
        bpy.ops.boxmarch.add_instance_on_curve(instance=cube.name, spacing=0.0)
    assert not curve.modifiers


@pytest.mark.slow
def test_preview_render_draws_the_others_when_one_object_is_bad(blender):
    bpy = blender
    from boxmarch import preview

    good = boxes(bpy, "Good")
    bad = boxes(bpy, "Bad", offset=0.5)
    for ob in (good, bad):
        ob.select_set(True)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    good.boxmarch.preview = bad.boxmarch.preview = True
    bad.data.vertices[0].co = (float("nan"), 0.0, 0.0)
    bad.data.update()
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    bpy.context.scene.collection.objects.link(camera)
    camera.location = (0.0, -30.0, 0.0)
    camera.rotation_euler = (np.pi / 2, 0.0, 0.0)
    with pytest.warns(RuntimeWarning, match="Bad"):
        rgba, _ = preview.render(bpy.context.scene, camera, 64, 48)
    assert (rgba[..., 3] > 0).sum() > 20
    assert [s.split(":")[0] for s in preview.last_skipped] == ["Bad"]


def test_integer_arguments_out_of_range_give_one_line(blender):
    arrays = scenes.box_arrays(np.zeros((1, 3)), np.ones((1, 3)), np.eye(3)[None])
    for call in (lambda: core.bake(*arrays, axis_turn=2**40), lambda: core.axis_turn_label(24),
                 lambda: core.merge_targets(arrays[0], np.zeros(8, np.int32), -1)):
        with pytest.raises(ValueError) as info:
            call()
        assert len(str(info.value)) < 120 and "\n" not in str(info.value)
    edges = arrays[1].copy()
    edges[0, 0] = -1
    with pytest.raises(ValueError, match="edge 0 names vertex -1"):
        core.remove_vertices(arrays[0], edges, *arrays[2:], np.zeros(8, np.uint8), np.zeros(24, np.int32))


# ---------------------------------------------------------------------------------------------
# command line: every check before the first byte is written


@pytest.mark.slow
def test_cli_never_writes_the_input_or_a_partial_set_of_outputs(baked_blend, tmp_path):
    before = digest(baked_blend)
    r = run_module(["export", str(baked_blend), "--preset", "BLENDER", "--to", str(baked_blend)], tmp_path)
    assert r.returncode == 2 and "is the input file" in r.stderr, r.stderr
    assert digest(baked_blend) == before
    (tmp_path / "out").mkdir()
    r = run_module(["export", str(baked_blend), "--to", "out/q.glb", "--out", "missing_dir/q.blend"], tmp_path)
    assert r.returncode == 2 and "missing_dir" in r.stderr, r.stderr
    assert not (tmp_path / "out" / "q.glb").exists()
    r = run_module(["export", str(baked_blend), "--to", "out/q.glb", "--out", "out/q.blend",
                    "--json", "nowhere/r.json"], tmp_path)
    assert r.returncode == 2 and "nowhere" in r.stderr, r.stderr
    assert not os.listdir(tmp_path / "out")
    r = run_module(["export", str(baked_blend), "--preset", "GLTF", "--to", "out/x.fbx"], tmp_path)
    assert r.returncode == 2 and "must end in .glb" in r.stderr, r.stderr
    assert not os.listdir(tmp_path / "out")
    r = run_module(["export", str(baked_blend), "--objects", "Baked", "Baked", "--to", "out/twice.glb"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert digest(baked_blend) == before


@pytest.mark.slow
def test_cli_messages_and_clamped_values(baked_blend, tmp_path):
    r = run_module([], tmp_path)
    assert r.returncode == 2 and "boxmarch: error: boxmarch:" not in r.stderr, r.stderr
    r = run_module(["pack-uv", str(baked_blend), "--padding", "-1"], tmp_path)
    assert r.returncode == 2 and "--padding must be" in r.stderr, r.stderr
    r = run_module(["dedup", str(baked_blend), "--tolerance", "inf"], tmp_path)
    assert r.returncode == 2 and "--tolerance must be" in r.stderr, r.stderr


def test_cli_read_only_out_folder_is_refused_first(baked_blend, tmp_path, monkeypatch, capsys):
    """Run in-process so that, as root (who may write into a mode 555 folder, so the kernel
    would let the write through), the folder can be made unwritable the way the kernel reports
    it to anyone else: os.access denies W_OK under it."""
    from boxmarch import cli

    locked = tmp_path / "locked"
    locked.mkdir()
    (tmp_path / "out").mkdir()
    locked.chmod(0o555)
    if os.geteuid() == 0:
        real_access = os.access
        monkeypatch.setattr(os, "access", lambda path, mode, *a, **k: (
            False if mode & os.W_OK and str(os.path.abspath(path)).startswith(str(locked))
            else real_access(path, mode, *a, **k)))
    monkeypatch.chdir(tmp_path)
    try:
        code = cli.run(["export", str(baked_blend), "--to", "out/q.glb", "--out", "locked/q.blend"])
    finally:
        locked.chmod(0o755)
    err = capsys.readouterr().err
    assert code == 2 and "locked" in err, err
    assert not os.listdir(tmp_path / "out")


# ---------------------------------------------------------------------------------------------
# round 2 (issue 21): the bake's own layers are never a tool's target; nothing to export


def test_pack_uv_refuses_the_baked_quaternion_maps_active_or_named(blender):
    bpy = blender
    ob = boxes(bpy)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    stored = mesh_io.read_uv(ob.data, mesh_io.QUAT_XY_UV).copy()
    ob.data.uv_layers.active = ob.data.uv_layers[mesh_io.QUAT_XY_UV]  # clicked in the UV Maps list
    with pytest.raises(RuntimeError, match=r"'BoxQuatXY' \(the active one\) holds the baked box frame.*'UVMap'"):
        bpy.ops.boxmarch.pack_uv_by_z()
    with pytest.raises(RuntimeError, match="'BoxQuatZW' holds the baked box frame"):
        bpy.ops.boxmarch.pack_uv_by_z(uv_map=mesh_io.QUAT_ZW_UV)
    assert np.array_equal(mesh_io.read_uv(ob.data, mesh_io.QUAT_XY_UV), stored)
    ob.data.uv_layers.active = ob.data.uv_layers["UVMap"]
    assert bpy.ops.boxmarch.pack_uv_by_z() == {"FINISHED"}  # the texture map packs; the frame stays
    assert worst_decode_error(bpy, ob) < 1e-5


def test_the_bake_refuses_an_unbaked_mesh_with_layers_named_as_its_own(blender):
    bpy = blender
    ob = boxes(bpy)
    for uv in list(ob.data.uv_layers):
        ob.data.uv_layers.remove(uv)
    ob.data.uv_layers.new(name=mesh_io.QUAT_XY_UV)  # the artist's only UV map, named so
    artist = np.random.default_rng(1).random((len(ob.data.loops), 2)).astype(np.float32)
    mesh_io.write_uv(ob.data, mesh_io.QUAT_XY_UV, artist)
    with pytest.raises(RuntimeError, match="holds no bake, yet has a UV map 'BoxQuatXY'.*rename"):
        bpy.ops.boxmarch.bake()
    assert [uv.name for uv in ob.data.uv_layers] == [mesh_io.QUAT_XY_UV]
    assert np.array_equal(mesh_io.read_uv(ob.data, mesh_io.QUAT_XY_UV), artist)
    assert ob.data.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE) is None
    ob.data.uv_layers[mesh_io.QUAT_XY_UV].name = "UVMap"  # as the message says
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert np.array_equal(mesh_io.read_uv(ob.data, "UVMap"), artist) and worst_decode_error(bpy, ob) < 1e-5


def test_a_baked_mesh_whose_faces_were_deleted_is_not_exported(blender, tmp_path):
    import bmesh

    from boxmarch.export import scene

    bpy = blender
    ob = boxes(bpy)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    bm = bmesh.new()
    bm.from_mesh(ob.data)
    bmesh.ops.delete(bm, geom=list(bm.faces), context="FACES_ONLY")  # the vertices and the layers stay
    bm.to_mesh(ob.data)
    bm.free()
    for preset, name in (("GLTF", "f.glb"), ("UNITY", "f.fbx")):
        with pytest.raises(scene.ExportInputError, match="mesh 'Boxes' has no faces"):
            scene.export_objects(bpy.context, [ob], preset, str(tmp_path / name))
    assert list(tmp_path.iterdir()) == []

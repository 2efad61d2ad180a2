"""Engine export presets, proved by round trip (docs/EXPORT.md).

glTF: the .glb is read back with tests/gltf_reader.py (written from the spec, not Blender's
importer) and every vertex is decoded with the shader's formula in glTF's own frame.
FBX (Unity): the file's raw numbers are read with Blender's FBX parser (tests/fbx_reader.py: no
axis conversion), put
in Unity's frame by negating x as Unity's importer does, and decoded; Blender's FBX importer must
give back exactly the numbers in the file. Expected values come from the box geometry and from
the closed forms derived in docs/EXPORT.md, never from the export code itself.
"""
import math
import os

import numpy as np
import pytest

from boxmarch import scenes
from boxmarch.formats import glb, transforms, presets
from tests.conftest import mesh_object
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb
from tests.helpers.menus import drawn_operators

HALF = math.sqrt(0.5)
# Blender object space -> glTF (x, z, -y); -> Unity (-x, z, -y).
TO_GLTF = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
TO_UNITY = np.array([[-1, 0, 0], [0, 0, 1], [0, -1, 0]], float)


def shader_origin(position, rgba, q):
    """docs/FORMAT.md: objPos + rotate_vector((rgb * 2 - 1) / a, q), in float64."""
    f = (rgba[:, :3] * 2.0 - 1.0) / rgba[:, 3:4]
    u, w = q[:, :3], q[:, 3:4]
    return position + f + 2.0 * np.cross(u, np.cross(u, f) + w * f)


def baked_boxes(bpy, count=120, seed=5, encoding="FLOAT_COLOR", domain="POINT"):
    # Small spread, sizable boxes: float32 positions then sit within 2e-6 of the half-extent of
    # the exact box corners, so the exact centres are a fair reference at 1e-5.
    arrays, centres, sizes, _ = scenes.random_boxes(count, seed=seed, spread=10.0, size_range=(0.5, 3.0))
    ob = mesh_object(bpy, "Boxes", *arrays)
    assert bpy.ops.boxmarch.bake(encoding=encoding, domain=domain) == {"FINISHED"}
    return ob, arrays[0], centres, sizes


def vertex_of(target_positions, blender_positions, axes):
    """Index of the Blender vertex behind each exported vertex: positions map exactly (a signed
    permutation of float32 values)."""
    lookup = {tuple(row): i for i, row in enumerate((blender_positions.astype(np.float64) @ axes.T)
                                                    .astype(np.float32).tolist())}
    return np.array([lookup[tuple(row)] for row in target_positions.astype(np.float32).tolist()])


def export(bpy, preset, path, layout="DEFAULT"):
    assert bpy.ops.boxmarch.export(filepath=str(path), preset=preset, layout=layout) == {"FINISHED"}
    assert path.exists()


@pytest.mark.parametrize("encoding, domain, tolerance", [
    ("FLOAT_COLOR", "POINT", 1e-5), ("FLOAT_COLOR", "CORNER", 1e-5),
    ("BYTE_COLOR", "POINT", 0.05)])  # 8-bit: the bake's own quantisation bound (docs/FORMAT.md)
def test_gltf_round_trip_lands_on_box_centres_in_gltf_frame(blender, tmp_path, encoding, domain, tolerance):
    ob, positions, centres, sizes = baked_boxes(blender, encoding=encoding, domain=domain)
    export(blender, "GLTF", tmp_path / "boxes.glb", layout="CLASSIC")
    meshes = read_glb(tmp_path / "boxes.glb")
    assert [m["name"] for m in meshes] == ["Boxes"]
    seen = np.zeros(len(positions), bool)
    for primitive in meshes[0]["primitives"]:
        assert primitive["_component_types"]["COLOR_0"] == 5126  # FLOAT: no 16-bit steps, no clipping
        vertex = vertex_of(primitive["POSITION"], positions, TO_GLTF)
        seen[vertex] = True
        q = np.concatenate([primitive["TEXCOORD_1"], primitive["TEXCOORD_2"]], axis=1)
        assert np.abs(np.linalg.norm(q, axis=1) - 1).max() < 1e-6
        origin = shader_origin(primitive["POSITION"], primitive["COLOR_0"], q)
        box = vertex // 8
        error = np.linalg.norm(origin - centres[box] @ TO_GLTF.T, axis=1) / (sizes[box].max(axis=1) / 2)
        assert error.max() <= tolerance, error.max()
    assert seen.all()


def test_gltf_keeps_texture_uvs_in_gltf_convention(blender, tmp_path):
    """Only the quaternion maps are compensated: the artist's UVMap is flipped as glTF wants."""
    ob, positions, _, _ = baked_boxes(blender, count=10)
    uv = ob.data.uv_layers["UVMap"]
    values = np.random.default_rng(0).uniform(0, 1, len(ob.data.loops) * 2).astype(np.float32)
    uv.data.foreach_set("uv", values)
    corner_verts = np.empty(len(ob.data.loops), np.int32)
    ob.data.loops.foreach_get("vertex_index", corner_verts)
    per_vertex = np.empty((len(positions), 2), np.float32)
    per_vertex[corner_verts] = values.reshape(-1, 2)
    # one UV per vertex so the exporter cannot split and reorder corners differently
    uv.data.foreach_set("uv", per_vertex[corner_verts].reshape(-1))
    export(blender, "GLTF", tmp_path / "uv.glb")
    primitive = read_glb(tmp_path / "uv.glb")[0]["primitives"][0]
    vertex = vertex_of(primitive["POSITION"], positions, TO_GLTF)
    expected = per_vertex[vertex].astype(np.float64)
    expected[:, 1] = 1.0 - expected[:, 1]
    assert np.abs(primitive["TEXCOORD_0"] - expected).max() < 1e-6


def unity_closed_form(q, rgba):
    """docs/EXPORT.md: Unity's quaternion sqrt(1/2) (x - w, -y - z, y - z, w + x) with w >= 0,
    and the offset's first channel mirrored (1 - r)."""
    x, y, z, w = q.T
    qu = HALF * np.stack([x - w, -y - z, y - z, w + x], 1)
    lead = np.where(qu[:, 3] != 0, qu[:, 3], np.where(qu[:, 0] != 0, qu[:, 0], np.where(qu[:, 1] != 0, qu[:, 1], qu[:, 2])))
    qu[lead < 0] *= -1
    out = rgba.copy()
    out[:, 0] = 1.0 - out[:, 0]
    return qu, out


@pytest.mark.parametrize("encoding, tolerance", [("FLOAT_COLOR", 1e-5), ("BYTE_COLOR", 0.05)])
def test_unity_fbx_decodes_in_unity_frame_and_reimports_exactly(blender, tmp_path, encoding, tolerance):
    bpy = blender
    ob, positions, centres, sizes = baked_boxes(bpy, encoding=encoding)
    mesh = ob.data
    corner_verts = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_verts)
    stored = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.color_attributes["BoxOffset"].data.foreach_get("color_srgb" if encoding == "BYTE_COLOR" else "color", stored)
    stored = stored.reshape(-1, 4)[corner_verts].astype(np.float64)
    if encoding == "BYTE_COLOR":
        stored = np.rint(stored * 255) / 255
    q = np.concatenate([np.array([d.uv[:] for d in mesh.uv_layers[name].data]) for name in ("BoxQuatXY", "BoxQuatZW")], 1)

    export(bpy, "UNITY", tmp_path / "boxes.fbx", layout="CLASSIC")
    raw = read_fbx_geometry(tmp_path / "boxes.fbx")
    # Unity's UV channels 0, 1, 2; the box parameters follow in 3-5 (docs/ENGINES.md)
    assert raw["uv_maps"] == ["UVMap", "BoxQuatXY", "BoxQuatZW", "BoxShapeMaterial", "BoxRandomUser", "BoxParentDepth"]
    assert raw["colours"] == ["BoxOffset"]  # Unity reads one colour layer: it must be ours
    assert raw["settings"]["UnitScaleFactor"] == 100.0  # metres: Unity's file scale is 1
    assert np.array_equal(raw["vertex"], corner_verts)
    # The file holds Blender's positions turned to Y-up, exactly (no scale).
    assert np.array_equal(raw["position"], positions.astype(np.float64)[corner_verts] @ TO_GLTF.T)
    expected_q, expected_rgba = unity_closed_form(q, stored)
    file_q = np.concatenate([raw["BoxQuatXY"], raw["BoxQuatZW"]], 1)
    assert np.abs(file_q - expected_q).max() < 2e-7
    assert np.abs(raw["BoxOffset"] - expected_rgba).max() < 2e-7
    if encoding == "BYTE_COLOR":  # bytes stay bytes: Unity's Color32 gets them back exactly
        file_bytes = raw["BoxOffset"] * 255
        assert np.abs(file_bytes - np.rint(file_bytes)).max() < 1e-4
        assert np.array_equal(np.rint(file_bytes), np.rint(expected_rgba * 255))
    # Unity's importer negates x; decode there with the shader's formula.
    origin = shader_origin(raw["position"] * [-1, 1, 1], raw["BoxOffset"], file_q)
    box = corner_verts // 8
    error = np.linalg.norm(origin - centres[box] @ TO_UNITY.T, axis=1) / (sizes[box].max(axis=1) / 2)
    assert error.max() <= tolerance, error.max()

    # Blender's importer converts positions back, but colours and UVs must come back untouched.
    bpy.ops.import_scene.fbx(filepath=str(tmp_path / "boxes.fbx"), colors_type="LINEAR")
    imported = next(o for o in bpy.context.selected_objects if o.type == "MESH").data
    assert len(imported.loops) == len(corner_verts)
    for name in ("BoxQuatXY", "BoxQuatZW"):
        uv = np.empty(len(imported.loops) * 2, np.float32)
        imported.uv_layers[name].data.foreach_get("uv", uv)
        assert np.array_equal(uv.reshape(-1, 2), raw[name].astype(np.float32))
        assert np.array_equal(raw[name].astype(np.float32).astype(np.float64), raw[name])  # float32 in the file
    colour = imported.color_attributes["BoxOffset"]
    values = np.empty(len(colour.data) * 4, np.float32)
    colour.data.foreach_get("color", values)
    values = values.reshape(-1, 4)
    if colour.domain == "POINT":
        imported_corner_verts = np.empty(len(imported.loops), np.int32)
        imported.loops.foreach_get("vertex_index", imported_corner_verts)
        values = values[imported_corner_verts]
    assert np.array_equal(values, raw["BoxOffset"].astype(np.float32))


def test_blender_preset_writes_the_baked_data_untouched(blender, tmp_path):
    bpy = blender
    ob, _, _, _ = baked_boxes(bpy, count=20)
    before = np.empty(len(ob.data.vertices) * 4, np.float32)
    ob.data.color_attributes["BoxOffset"].data.foreach_get("color", before)
    export(bpy, "BLENDER", tmp_path / "raw.blend")
    with bpy.data.libraries.load(str(tmp_path / "raw.blend")) as (src, dst):
        assert src.objects == ["Boxes"]
        dst.meshes = src.meshes
    loaded = dst.meshes[0]
    after = np.empty(len(loaded.vertices) * 4, np.float32)
    loaded.color_attributes["BoxOffset"].data.foreach_get("color", after)
    assert np.array_equal(before, after)


def test_export_leaves_the_scene_as_it_was(blender, tmp_path):
    bpy = blender
    ob, _, _, _ = baked_boxes(bpy, count=20)
    other = mesh_object(bpy, "Other", *scenes.random_boxes(2, seed=1)[0], select=False)
    ob.select_set(True)
    mesh_names = sorted(m.name for m in bpy.data.meshes)
    uv_before = np.array([d.uv[:] for d in ob.data.uv_layers["BoxQuatZW"].data])
    for preset, name in (("GLTF", "a.glb"), ("UNITY", "a.fbx")):
        export(bpy, preset, tmp_path / name)
    assert sorted(m.name for m in bpy.data.meshes) == mesh_names
    assert ob.data.name == "Boxes" and other.data.name == "Other"
    assert np.array_equal(np.array([d.uv[:] for d in ob.data.uv_layers["BoxQuatZW"].data]), uv_before)
    assert ob.select_get() and not other.select_get()
    assert sorted(os.listdir(tmp_path)) == ["a.boxes.bin", "a.boxmarch.json", "a.fbx", "a.glb"]  # no partial files left


def test_export_refuses_unbaked_mesh_and_writes_nothing(blender, tmp_path):
    bpy = blender
    mesh_object(bpy, "Raw", *scenes.random_boxes(3, seed=2)[0])
    with pytest.raises(RuntimeError, match="not baked"):
        bpy.ops.boxmarch.export(filepath=str(tmp_path / "x.glb"), preset="GLTF")
    assert os.listdir(tmp_path) == []


def test_export_operator_is_in_file_export_menu(blender):
    from boxmarch.operators import export as export_ops

    listed = drawn_operators(blender.types.TOPBAR_MT_file_export.draw)
    assert {export_ops.BOXMARCH_OT_export.bl_idname, export_ops.BOXMARCH_OT_quick_export.bl_idname} <= set(listed)


def test_exporter_index_colours_come_back_exactly():
    """The vertex index the glTF preset hands the exporter as a colour survives the exporter's
    16-bit rounding (c * 65535 + 0.5, truncated) for every index up to 2^32 - 1."""
    count = 70000
    colours = glb.index_colours(count)
    rounded = (colours * np.float32(65535) + np.float32(0.5)).astype(np.uint16).astype(np.int64)
    assert np.array_equal(rounded[:, 0] + (rounded[:, 1] << 16), np.arange(count))


def test_target_quaternions_match_closed_forms():
    rng = np.random.default_rng(4)
    q = rng.normal(size=(500, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1
    x, y, z, w = q.T
    gltf = HALF * np.stack([x - w, y + z, z - y, w + x], 1)
    gltf[gltf[:, 3] < 0] *= -1
    assert np.abs(transforms.target_quaternions(q, presets.PRESETS["GLTF"]) - gltf).max() < 1e-12
    unity, _ = unity_closed_form(q, np.zeros((500, 4)))
    assert np.abs(transforms.target_quaternions(q, presets.PRESETS["UNITY"]) - unity).max() < 1e-12
    assert np.abs(transforms.target_quaternions(q, presets.PRESETS["BLENDER"]) - q).max() < 1e-12


def test_preset_rotation_is_a_quarter_turn_about_x():
    """Z-up to Y-up, (x, y, z) -> (x, z, -y), is -90 degrees about x: q = (-sqrt(1/2), 0, 0, sqrt(1/2))."""
    q = transforms.matrix_quaternions(presets.Z_UP_TO_Y_UP)[0]
    assert np.abs(q - [-HALF, 0, 0, HALF]).max() < 1e-15


def test_unity_export_warns_about_float_offsets(blender, tmp_path):
    from boxmarch.export import scene

    ob, _, _, _ = baked_boxes(blender, count=5)
    report = scene.export_objects(blender.context, [ob], "UNITY", str(tmp_path / "w.fbx"), "CLASSIC")
    assert len(report["warnings"]) == 1 and "Color32" in report["warnings"][0]
    assert blender.ops.boxmarch.bake(encoding="BYTE_COLOR") == {"FINISHED"}
    assert scene.export_objects(blender.context, [ob], "UNITY", str(tmp_path / "w.fbx"), "CLASSIC")["warnings"] == []


@pytest.mark.parametrize("preset, name", [("GODOT3", "w.glb"), ("UNITY", "w.fbx"), ("UNREAL", "w.fbx")])
def test_default_import_loss_is_one_note_not_a_warning(blender, tmp_path, preset, name):
    """The export writes what sets the engine's import (Godot 3: NAME.glb.import with compression
    off; Unity and Unreal: the sidecar their helpers read), so what the default import would cost
    is said once, in the import note, and is no warning."""
    from boxmarch.export import scene

    ob, _, _, _ = baked_boxes(blender, count=5)
    report = scene.export_objects(blender.context, [ob], preset, str(tmp_path / name))
    assert report["default_import_error"] > 1e-4
    assert report["warnings"] == [], report["warnings"]
    note = scene.import_note(report)
    assert note.startswith(presets.PRESETS[preset].import_settings) and f"{report['default_import_error']:.1e}" in note
    if preset == "GODOT3":
        assert "compress=false" in (tmp_path / "w.glb.import").read_text()


def test_quick_export_repeats_the_last_preset_and_file(blender, tmp_path):
    bpy = blender
    baked_boxes(bpy, count=5)
    with pytest.raises(RuntimeError, match="Nothing exported yet"):
        bpy.ops.boxmarch.quick_export()
    export(bpy, "GLTF", tmp_path / "q.glb")
    (tmp_path / "q.glb").unlink()
    assert bpy.ops.boxmarch.quick_export() == {"FINISHED"}
    assert read_glb(tmp_path / "q.glb")[0]["name"] == "Boxes"


def test_object_transforms_and_shared_meshes_keep_mesh_space_exact(blender, tmp_path):
    """The decode works in object (mesh) space: turned, scaled and instanced objects must reach
    the file with the mesh data in the target's object frame, the transform on the node."""
    bpy = blender
    ob, positions, centres, sizes = baked_boxes(bpy, count=30)
    ob.rotation_euler = (0.3, -1.1, 2.0)
    ob.scale = (2.0, 0.5, 1.5)
    ob.location = (5.0, -3.0, 7.0)
    twin = bpy.data.objects.new("Twin", ob.data)  # a second object sharing the mesh
    bpy.context.scene.collection.objects.link(twin)
    twin.select_set(True)
    export(bpy, "GLTF", tmp_path / "t.glb", layout="CLASSIC")
    meshes = read_glb(tmp_path / "t.glb")
    assert [m["name"] for m in meshes] == ["Boxes"]  # one mesh, two nodes
    primitive = meshes[0]["primitives"][0]
    vertex = vertex_of(primitive["POSITION"], positions, TO_GLTF)  # raises KeyError if transformed
    q = np.concatenate([primitive["TEXCOORD_1"], primitive["TEXCOORD_2"]], axis=1)
    origin = shader_origin(primitive["POSITION"], primitive["COLOR_0"], q)
    box = vertex // 8
    assert (np.linalg.norm(origin - centres[box] @ TO_GLTF.T, axis=1) / (sizes[box].max(axis=1) / 2)).max() < 1e-5
    export(bpy, "UNITY", tmp_path / "t.fbx")
    raw = read_fbx_geometry(tmp_path / "t.fbx")
    corner_verts = np.empty(len(ob.data.loops), np.int32)
    ob.data.loops.foreach_get("vertex_index", corner_verts)
    assert np.array_equal(raw["position"], positions.astype(np.float64)[corner_verts] @ TO_GLTF.T)


@pytest.mark.parametrize("layout, channels", [
    ("CLASSIC", {"COLOR_0": "VEC4", "TEXCOORD_1": "VEC2", "TEXCOORD_2": "VEC2"}),
    ("NORMAL_FRAME", {"NORMAL": "VEC3", "TANGENT": "VEC4", "TEXCOORD_1": "VEC2", "TEXCOORD_4": "VEC2"})])
def test_patched_glb_is_tidy(blender, tmp_path, layout, channels):
    """After the channels are written: every accessor and buffer view is used, views are 4-byte
    aligned inside the one buffer, and the buffer's length is the BIN chunk's."""
    import json
    import struct

    baked_boxes(blender, count=8)
    export(blender, "GLTF", tmp_path / "t.glb", layout=layout)
    data = (tmp_path / "t.glb").read_bytes()
    json_length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_length])
    bin_length = struct.unpack_from("<I", data, 20 + json_length)[0]
    used = {i for m in doc["meshes"] for p in m["primitives"] for i in [*p["attributes"].values(), p.get("indices")]
            if i is not None}
    assert used == set(range(len(doc["accessors"])))
    assert {a["bufferView"] for a in doc["accessors"]} | {i["bufferView"] for i in doc.get("images", [])
                                                          if "bufferView" in i} == set(range(len(doc["bufferViews"])))
    assert all(v.get("byteOffset", 0) % 4 == 0 and v.get("byteOffset", 0) + v["byteLength"] <= bin_length
               for v in doc["bufferViews"])
    assert doc["buffers"][0]["byteLength"] == bin_length
    attributes = doc["meshes"][0]["primitives"][0]["attributes"]
    for name, kind in channels.items():
        accessor = doc["accessors"][attributes[name]]
        assert (accessor["componentType"], accessor["type"], accessor.get("normalized", False)) == (5126, kind, False)


def test_glb_patch_refuses_a_foreign_index(blender, tmp_path):
    from boxmarch.formats import glb as glb_io

    baked_boxes(blender, count=2)
    export(blender, "GLTF", tmp_path / "t.glb")
    gltf, binary = glb_io.read(tmp_path / "t.glb")
    with pytest.raises(ValueError, match="wrote no mesh named"):
        glb_io.replace_vertex_channels(gltf, binary, {"Elsewhere": {"COLOR": np.zeros((16, 4), np.float32)}})
    with pytest.raises(ValueError, match="not a glTF binary"):
        glb_io.read(__file__)

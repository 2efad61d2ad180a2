"""Vertices and bytes per box in every engine export (docs/FORMAT.md, *Vertices and bytes per box*).

Every vertex of a box carries the same frame, half-extents, index and parameters, and an offset
that depends on the vertex only, so a box needs its 8 corners and no more. The export's copy
must not split them: no UV map whose values differ between the corners of one vertex where the
artist gave none, and one normal per vertex in the layouts whose decode reads no normal (a flat
box would be 24). Counted from the written files with the tests' own readers
(tests/helpers/file_vertices.py); the expected bytes per vertex are the sums of the channels
docs/ENGINES.md lists per layout (float32: position 12, normal 12, tangent 16 in glTF and 12
plus a 12-byte binormal in FBX, a UV 8, a colour 16), the triangles 12 per box."""
import json
import pathlib

import numpy as np
import pytest

from boxmarch.formats import presets
from tests.conftest import random_boxes_object
from tests.helpers.file_vertices import flatten, model_counts

BOXES = 24
# (preset, layout): float32 bytes of one vertex, from the channel tables of docs/ENGINES.md
VERTEX_BYTES = {
    ("GLTF", "NORMAL_FRAME"): 12 + 12 + 16 + 8 * 8,   # POSITION, NORMAL, TANGENT, TEXCOORD_0..7
    ("GLTF", "UV_FRAME"): 12 + 12 + 8 * 8,            # POSITION, NORMAL, TEXCOORD_0..7
    ("GLTF", "CLASSIC"): 12 + 12 + 6 * 8 + 16,        # POSITION, NORMAL, TEXCOORD_0..5, COLOR_0
    ("GODOT3", "NORMAL_COLOR"): 12 + 12 + 16 + 8 + 16,  # POSITION, NORMAL, TANGENT, TEXCOORD_0, COLOR_0
    ("UNITY", "UV_FRAME"): 12 + 12 + 8 * 8,
    ("UNITY", "CLASSIC"): 12 + 12 + 6 * 8 + 16,
    ("UNITY", "NORMAL_FRAME"): 12 + 12 + 12 + 12 + 8 * 8,  # normal, tangent, binormal, 8 UV maps
    ("UNREAL", "UV_FRAME"): 12 + 12 + 8 * 8,
}


def test_every_engine_layout_is_counted():
    assert set(VERTEX_BYTES) == {(name, layout) for name, p in presets.PRESETS.items() if not p.raw_blend
                                 for layout in p.layouts}


def assert_8_vertices_a_box(path, name, layout, boxes=BOXES):
    counts = model_counts(path)
    index_width = 2 if path.suffix == ".glb" else 4  # glTF: uint16 below 65,536 vertices
    per_box = (counts["vertices"] * counts["vertex_bytes"] + counts["index_bytes"]) / boxes
    vertex_bytes = VERTEX_BYTES[name, layout]
    assert (counts["vertices"] / boxes, counts["triangles"], counts["vertex_bytes"], per_box) == \
        (8, 12 * boxes, vertex_bytes, 8 * vertex_bytes + 36 * index_width), (name, layout, counts["attributes"])


@pytest.mark.parametrize("faces", ["smooth", "flat"])
def test_every_export_writes_8_vertices_per_box(blender, tmp_path, faces):
    bpy = blender
    ob = random_boxes_object(bpy, count=BOXES)
    if faces == "flat":
        flatten(bpy, ob.data)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    for name, layout in VERTEX_BYTES:
        path = tmp_path / f"{name}_{layout}{presets.PRESETS[name].extension}"
        assert bpy.ops.boxmarch.export(filepath=str(path), preset=name, layout=layout) == {"FINISHED"}
        assert_8_vertices_a_box(path, name, layout)


@pytest.mark.slow
def test_blender_34_exports_write_8_vertices_per_box(blender, tmp_path, package_parent):
    """The same in Debian's Blender 3.4 program (its exporters, auto smooth and custom normals of
    before 4.1): tests/blender_scripts/export_bytes_check.py exports, this process counts."""
    from tests.helpers.blender_program import SCRIPTS, run_blender

    run_blender(["--background", "--factory-startup", "--python-exit-code", "1", "--python",
                 str(SCRIPTS / "export_bytes_check.py"), "--", str(package_parent),
                 str(pathlib.Path(__file__).parent.parent), str(tmp_path), str(BOXES)], tmp_path)
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["version"][:2] == [3, 4]
    assert sorted(result["files"]) == sorted(f"{faces} {name} {layout}" for faces in ("smooth", "flat")
                                             for name, layout in VERTEX_BYTES)
    for key, file_name in result["files"].items():
        _faces, name, layout = key.split()
        assert_8_vertices_a_box(tmp_path / file_name, name, layout)


def test_artist_uvs_that_differ_per_corner_are_kept(blender, tmp_path):
    """The artist's UV map is texture data: where its corners of one vertex differ, the file keeps
    every distinct (vertex, UV) pair, and the values (glTF's 1 - v)."""
    bpy = blender
    ob = random_boxes_object(bpy, count=BOXES)
    mesh = ob.data
    uv = mesh.uv_layers.new(name="UVMap")
    corner_uv = np.random.default_rng(1).integers(0, 4, (len(mesh.loops), 2)).astype(np.float32) / 4
    uv.data.foreach_set("uv", corner_uv.reshape(-1))
    corner_vertex = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vertex)
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    pairs = np.unique(np.column_stack([corner_vertex, corner_uv]), axis=0)
    path = tmp_path / "uv.glb"
    assert bpy.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    assert model_counts(path)["vertices"] == len(pairs) > 8 * BOXES


def test_a_bake_from_before_gets_8_vertices_after_its_uv_maps_are_removed(blender, tmp_path):
    """A bake before the zero placeholder left Blender's default fill in UVMap: the export keeps
    it as the artist's (20 vertices a box); removing the three UV maps and baking again gives 8
    (docs/FORMAT.md)."""
    bpy = blender
    ob = random_boxes_object(bpy, count=BOXES)
    ob.data.uv_layers.new(name="UVMap")  # Blender's default fill, as the bake made it before
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert bpy.ops.boxmarch.export(filepath=str(tmp_path / "before.glb"), preset="GLTF") == {"FINISHED"}
    for name in ("UVMap", "BoxQuatXY", "BoxQuatZW"):
        ob.data.uv_layers.remove(ob.data.uv_layers[name])
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert bpy.ops.boxmarch.export(filepath=str(tmp_path / "after.glb"), preset="GLTF") == {"FINISHED"}
    assert model_counts(tmp_path / "before.glb")["vertices"] == 20 * BOXES
    assert_8_vertices_a_box(tmp_path / "after.glb", "GLTF", "NORMAL_FRAME")

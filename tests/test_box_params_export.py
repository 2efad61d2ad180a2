"""Box parameters, parents and depths through every preset's file: painted in Blender with
known values, exported, read back with the tests' own file readers (tests/gltf_reader.py,
tests/fbx_reader.py, the .tres / .bin table) and decoded as docs/ENGINES.md states for each
layout: integers exact, floats within 1e-6. The random value is compared with the one the bake
stored (read raw from the mesh), which the painted values cannot give."""
import json

import numpy as np
import pytest

from boxmarch import scenes
from boxmarch.export import scene as export_scene
from boxmarch.formats.presets import PRESETS
from tests.conftest import mesh_object
from tests.engine_scene import TO_Y_UP, UNITY, UNREAL, table_texels
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb
from tests.helpers import sidecar_files

SPACING = 1.5
# Two meshes: boxes at x = 1.5 k, k = 0..5 (mesh A) and 10..14 (mesh B); k names the box in any file.
KEYS = {"A": np.arange(6), "B": np.arange(10, 15)}
SHAPE = {"A": [0, 1, 2, 3, 4, 5], "B": [6, 5, 4, 3, 2]}
MATERIAL = {"A": [7, 8, 7, 8, 7, 8], "B": [1, 2, 3, 4, 5]}
USER = {"A": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], "B": [-1.25, 2.5, 1e-3, 7.0, 0.0]}
PARENT = {"A": [-1, 0, 1, 2, 0, 4], "B": [-1, 0, 0, 2, 3]}
DEPTH = {"A": [0, 1, 2, 3, 1, 2], "B": [0, 1, 1, 2, 3]}


def painted_object(blender, name):
    keys = KEYS[name]
    centres = np.stack([SPACING * keys, np.zeros(len(keys)), np.zeros(len(keys))], 1)
    ob = mesh_object(blender, name, *scenes.box_arrays(centres, 1.0, np.eye(3)), select=True)
    mesh = ob.data
    for attr, values, kind in (("boxmarch_shape", SHAPE, "INT"), ("boxmarch_material", MATERIAL, "INT"),
                               ("boxmarch_user", USER, "FLOAT"), ("boxmarch_parent", PARENT, "INT")):
        mesh.attributes.new(attr, kind, "FACE").data.foreach_set("value", np.repeat(values[name], 6))
    return ob


@pytest.fixture
def scene(blender):
    objects = [painted_object(blender, name) for name in ("A", "B")]
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    random = {}
    for ob in objects:
        stored = np.empty(len(ob.data.vertices) * 2, np.float32)
        ob.data.attributes[".boxmarch_random_user"].data.foreach_get("vector", stored)
        random[ob.name] = stored.reshape(-1, 2)[::8, 0]
    return objects, random


def expected(name, random, index_base):
    """Per box of mesh ``name``: shape, material, random, user, parent (file numbering), depth."""
    parent = np.array(PARENT[name])
    return np.stack([SHAPE[name], MATERIAL[name], random[name], USER[name],
                     np.where(parent >= 0, parent + index_base, -1), DEPTH[name]], 1).astype(np.float64)


def check(values, keys, name, random, index_base):
    """values (n, 6) decoded per file vertex whose box key is ``keys``."""
    want = expected(name, random, index_base)[keys - KEYS[name][0]]
    ints = [0, 1, 4, 5]
    assert np.array_equal(values[:, ints], want[:, ints])
    assert np.abs(values[:, [2, 3]] - want[:, [2, 3]]).max() <= 1e-6


def box_key(x):
    return np.rint(np.asarray(x, np.float64) / SPACING).astype(int)


def decode_vertex_channels(layout, uv):
    """(n, 6) shape, material, random, user, parent, depth from a layout's per-vertex UV channels
    (docs/ENGINES.md), or None where a value rides in the box table only (NaN columns)."""
    nan = np.full(len(uv[1]), np.nan)
    if layout == "CLASSIC":
        return np.stack([uv[3][:, 0], uv[3][:, 1], uv[4][:, 0], uv[4][:, 1], uv[5][:, 0], uv[5][:, 1]], 1)
    if layout == "NORMAL_FRAME":
        return np.stack([uv[5][:, 0], uv[5][:, 1], uv[6][:, 0], uv[6][:, 1], uv[7][:, 0], uv[7][:, 1]], 1)
    if layout == "UV_FRAME":  # random, user and depth: the box table only
        return np.stack([uv[7][:, 0], uv[7][:, 1], nan, nan, uv[6][:, 1], nan], 1)
    raise ValueError(layout)


def index_of(layout, uv):
    return {"UV_FRAME": uv[4][:, 1], "NORMAL_FRAME": uv[2][:, 1]}.get(layout)


def table_rows(texels, width, boxes, index):
    """(n, 6) from the box table's three planes (docs/ENGINES.md): plane 0 = (h, parent),
    plane 1 = (shape, material, random, user), plane 2 = (depth, 0, 0, 0)."""
    rows_per_plane = -(-boxes // width)
    i = np.rint(index).astype(int)
    at = lambda plane: texels[(plane * rows_per_plane + i // width) * width + i % width]
    return np.concatenate([at(1), at(0)[:, 3:4], at(2)[:, :1]], 1)


def rotate(v, q):
    """v turned by unit quaternions q (x, y, z, w), as docs/FORMAT.md states the decode."""
    u, w = q[:, :3], q[:, 3:]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def check_table_frames(texels, width, boxes, index, positions, offsets, keys, to_engine, scale):
    """The table's planes 3 (origin) and 4 (frame) of each vertex's box: the origin is the box's
    known centre in the engine's frame, and position + R(q) f, with f from the layout's
    channels, lands on it (within 1e-6 of the half-extent)."""
    rows_per_plane = -(-boxes // width)
    i = np.rint(index).astype(int)
    at = lambda plane: texels[(plane * rows_per_plane + i // width) * width + i % width].astype(np.float64)
    origin, q = at(3)[:, :3], at(4)
    centre = np.stack([SPACING * keys, 0 * keys, 0 * keys], 1) @ to_engine.T
    half = 0.5 * scale
    assert np.abs(origin - centre).max() <= 1e-6 * half + 2e-7 * np.abs(centre).max()
    assert np.abs(positions + rotate(offsets, q) - origin).max() <= 1e-6 * half + 2e-7 * np.abs(centre).max()


def merge_table(vertex_values, table_values):
    out = vertex_values.copy()
    missing = np.isnan(out)
    out[missing] = table_values[missing]
    assert np.array_equal(np.isnan(out), np.zeros_like(out, bool))
    present = ~missing  # values carried twice must agree exactly
    assert np.array_equal(vertex_values[present], table_values[present])
    return out


def decode_by_sidecar(bpy, path, sidecar):
    """(file positions, (n, 6) shape, material, random, user, parent, depth) of ``path`` read
    through its sidecar alone: each value where box_parameters says it rides, a vertex channel
    found by its file_channels name, or the texel of the vertex's index in the box_table."""
    positions, channels = sidecar_files.file_channels(bpy, path, sidecar)
    table, columns = sidecar["box_table"], []
    for name in ("shape", "material", "random", "user", "parent", "depth"):
        spec = sidecar["box_parameters"][name]
        if not spec.startswith("TABLE."):
            columns.append(sidecar_files.values(channels, [spec])[:, 0])
            continue
        plane, component = int(spec.split(".")[1]), "rgba".index(spec.split(".")[2])
        assert table["planes"][plane][component] == name
        data = path.parent / table["file"]
        texels = (table_texels(data.read_text()) if table["format"] == "godot3_tres"
                  else np.fromfile(data, "<f4").reshape(-1, 4))
        index = np.rint(sidecar_files.values(channels, sidecar["quantities"]["index"]["channels"])[:, 0]).astype(int)
        rows, width = table["height"] // len(table["planes"]), table["width"]
        columns.append(texels[(plane * rows + index // width) * width + index % width, component])
    return positions, np.stack(columns, 1).astype(np.float64)


@pytest.mark.parametrize("preset, layout", [(name, layout) for name, preset in PRESETS.items() for layout in preset.layouts])
def test_every_export_decodes_its_parameters_from_the_sidecar_alone(blender, scene, tmp_path, preset, layout):
    """Mesh A exported with each preset and layout, its file read only where its sidecar points
    (file_channels, box_parameters, box_table, axes.v_flipped_in_file): the painted values."""
    objects, random = scene
    objects[1].select_set(False)  # one mesh: the FBX reader reads a file's first geometry
    path = tmp_path / f"p{PRESETS[preset].extension}"
    assert blender.ops.boxmarch.export(filepath=str(path), preset=preset, layout=layout) == {"FINISHED"}
    sidecar = json.loads((tmp_path / "p.boxmarch.json").read_text())
    positions, decoded = decode_by_sidecar(blender, path, sidecar)
    check(decoded, box_key(positions[:, 0]), "A", random, 0)


@pytest.mark.parametrize("layout", ["NORMAL_FRAME", "UV_FRAME", "CLASSIC"])
def test_gltf(blender, scene, tmp_path, layout):
    _, random = scene
    path = tmp_path / "p.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF", layout=layout) == {"FINISHED"}
    texels = None if layout == "CLASSIC" else np.fromfile(tmp_path / "p.boxes.bin", "<f4").reshape(-1, 4)
    base = 0
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        uv = {n: p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 8) if f"TEXCOORD_{n}" in p}
        values = decode_vertex_channels(layout, uv)
        keys = box_key(p["POSITION"][:, 0])
        if texels is not None:
            values = merge_table(values, table_rows(texels, 11, 11, index_of(layout, uv)))
            offsets = np.concatenate([uv[1], uv[2][:, :1]] if layout == "NORMAL_FRAME" else [uv[3], uv[4][:, :1]], 1)
            check_table_frames(texels, 11, 11, index_of(layout, uv), p["POSITION"].astype(np.float64), offsets, keys,
                               TO_Y_UP, 1.0)
        check(values, keys, mesh["name"], random, base)
        base += len(KEYS[mesh["name"]]) if layout != "CLASSIC" else 0
    assert base == (11 if layout != "CLASSIC" else 0)


def test_godot3_table(blender, scene, tmp_path):
    _, random = scene
    path = tmp_path / "g.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GODOT3") == {"FINISHED"}
    texels = table_texels((tmp_path / "g.boxes.tres").read_text())
    base = 0
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        colour = p["COLOR_0"].astype(np.float64)
        values = table_rows(texels, 11, 11, colour[:, 3])
        keys = box_key(p["POSITION"][:, 0])
        check(values, keys, mesh["name"], random, base)
        check_table_frames(texels, 11, 11, colour[:, 3], p["POSITION"].astype(np.float64), colour[:, :3], keys,
                           TO_Y_UP, 1.0)
        base += len(KEYS[mesh["name"]])


@pytest.mark.parametrize("preset, layout", [("UNITY", "UV_FRAME"), ("UNITY", "CLASSIC"), ("UNITY", "NORMAL_FRAME"),
                                            ("UNREAL", "UV_FRAME")])
def test_fbx(blender, scene, tmp_path, preset, layout):
    objects, random = scene
    objects[1].select_set(False)  # the reader reads the file's first geometry: mesh A alone
    path = tmp_path / "f.fbx"
    assert blender.ops.boxmarch.export(filepath=str(path), preset=preset, layout=layout) == {"FINISHED"}
    raw = read_fbx_geometry(path)
    names = {"CLASSIC": ["BoxQuatXY", "BoxQuatZW", "BoxShapeMaterial", "BoxRandomUser", "BoxParentDepth"],
             "UV_FRAME": ["BoxQuatXY", "BoxQuatZW", "BoxOffsetXY", "BoxOffsetZIndex", "BoxHalfXY", "BoxHalfZ",
                          "BoxShapeMaterial"],
             "NORMAL_FRAME": ["BoxOffsetXY", "BoxOffsetZIndex", "BoxHalfXY", "BoxHalfZ", "BoxShapeMaterial",
                              "BoxRandomUser", "BoxParentDepth"]}[layout]
    assert raw["uv_maps"][1:] == names  # UV1.. in file order after the artist's UV0
    uv = {n: raw[name].copy() for n, name in enumerate(names, 1)}
    if preset == "UNREAL":  # its importer reads v as 1 - v
        for values in uv.values():
            values[:, 1] = 1.0 - values[:, 1]
    values = decode_vertex_channels(layout, uv)
    keys = box_key(raw["position"][:, 0])
    if layout != "CLASSIC":
        texels = np.fromfile(tmp_path / "f.boxes.bin", "<f4").reshape(-1, 4)
        values = merge_table(values, table_rows(texels, 6, 6, index_of(layout, uv)))
        engine = UNITY if preset == "UNITY" else UNREAL
        offsets = np.concatenate([uv[1], uv[2][:, :1]] if layout == "NORMAL_FRAME" else [uv[3], uv[4][:, :1]], 1)
        check_table_frames(texels, 6, 6, index_of(layout, uv), raw["position"] @ engine["from_file"].T,
                           offsets, keys, engine["to_engine"], engine["scale"])
    check(values, keys, "A", random, 0)


def test_shuffled_ids_fail_the_check(blender, scene, tmp_path):
    """Negative control: the same decode against shape ids in another order must fail."""
    _, random = scene
    path = tmp_path / "p.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    (p,) = read_glb(path)[0]["primitives"]
    values = decode_vertex_channels("NORMAL_FRAME", {n: p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 8)})
    keys = box_key(p["POSITION"][:, 0])
    check(values, keys, "A", random, 0)
    values[:, 0] = np.array(SHAPE["A"])[::-1][keys]
    with pytest.raises(AssertionError):
        check(values, keys, "A", random, 0)


@pytest.mark.parametrize("layout", ["NORMAL_FRAME", "UV_FRAME"])
def test_object_parent_gives_the_roots_a_parent_box(blender, scene, tmp_path, layout):
    """Object B under object A, moved so that B's root box (key 10, at x = 15 in B) lies at
    x = 3 in the world, on A's box 2 (depth 2): the file gives it parent 2 and depth 3, and
    B's other boxes keep their parents in B with 3 added to their depths. A is unchanged."""
    objects, random = scene
    a, b = objects
    b.parent = a
    b.location = (-12.0, 0.0, 0.0)
    blender.context.view_layer.update()
    path = tmp_path / "p.glb"
    report = export_scene.export_objects(blender.context, objects, "GLTF", str(path), layout)
    assert report["meshes"][0]["box_parameters"].get("object_parent") is None
    assert report["meshes"][1]["box_parameters"]["object_parent"] == {"object": "A", "mesh": "A", "linked_roots": 1}
    assert report["meshes"][1]["box_parameters"]["max_depth"] == 6
    texels = np.fromfile(tmp_path / "p.boxes.bin", "<f4").reshape(-1, 4)
    want = {"A": (PARENT["A"], DEPTH["A"]), "B": ([2, 6, 6, 8, 9], [3, 4, 4, 5, 6])}
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        uv = {n: p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 8) if f"TEXCOORD_{n}" in p}
        values = merge_table(decode_vertex_channels(layout, uv), table_rows(texels, 11, 11, index_of(layout, uv)))
        rows = box_key(p["POSITION"][:, 0]) - KEYS[mesh["name"]][0]
        parent, depth = want[mesh["name"]]
        assert np.array_equal(values[:, 4], np.array(parent)[rows])
        assert np.array_equal(values[:, 5], np.array(depth)[rows])


def test_object_parents_chain_in_any_export_order(blender, scene, tmp_path):
    """C (one box at x = 20 in C) under B under A, exported first: A's boxes number from 1, B's
    from 7. B moved as above: B's root takes A's box 2 (file 3, depth 3); C's box lies at x = 8
    in the world, nearest B's box key 13 (x = 7.5: row 3, file 10, depth 2 + 3 = 5), so C's box
    has parent 10 and depth 6."""
    (a, b), _ = scene
    c = mesh_object(blender, "C", *scenes.box_arrays(np.array([[20.0, 0.0, 0.0]]), 1.0, np.eye(3)))
    for ob in blender.context.selected_objects:
        ob.select_set(ob == c)
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    b.parent, c.parent = a, b
    b.location = (-12.0, 0.0, 0.0)
    blender.context.view_layer.update()
    path = tmp_path / "p.glb"
    report = export_scene.export_objects(blender.context, [c, a, b], "GLTF", str(path), "NORMAL_FRAME")
    assert [m["mesh"] for m in report["meshes"]] == ["C", "A", "B"]
    assert report["meshes"][0]["box_parameters"]["object_parent"] == {"object": "B", "mesh": "B", "linked_roots": 1}
    want = {"C": ([10], [6]), "A": ([-1, 1, 2, 3, 1, 5], DEPTH["A"]), "B": ([3, 7, 7, 9, 10], [3, 4, 4, 5, 6])}
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        parent_depth = p["TEXCOORD_7"].astype(np.float64)
        keys = box_key(p["POSITION"][:, 0])
        rows = np.zeros_like(keys) if mesh["name"] == "C" else keys - KEYS[mesh["name"]][0]  # C: one box
        parent, depth = want[mesh["name"]]
        assert np.array_equal(parent_depth[:, 0], np.array(parent)[rows])
        assert np.array_equal(parent_depth[:, 1], np.array(depth)[rows])


def test_object_parent_in_classic_is_reported_not_written(blender, scene, tmp_path):
    objects, random = scene
    objects[1].parent = objects[0]
    report = export_scene.export_objects(blender.context, objects, "GLTF", str(tmp_path / "c.glb"), "CLASSIC")
    assert report["meshes"][1]["box_parameters"]["object_parent"]["linked_roots"] == 0
    assert any("CLASSIC numbers boxes per mesh" in w for w in report["warnings"])
    (p,) = next(mesh for mesh in read_glb(tmp_path / "c.glb") if mesh["name"] == "B")["primitives"]
    values = decode_vertex_channels("CLASSIC", {n: p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 6)})
    check(values, box_key(p["POSITION"][:, 0]), "B", random, 0)  # B's own parents and depths, unchanged


def test_object_parent_control_without_the_move_fails(blender, scene, tmp_path):
    """Negative control: unmoved, B's root lies nearest A's box 5 (x = 15 against 7.5), so the
    parents expected above do not hold."""
    objects, _ = scene
    objects[1].parent = objects[0]
    path = tmp_path / "p.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    (p,) = next(mesh for mesh in read_glb(path) if mesh["name"] == "B")["primitives"]
    uv = {n: p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 8)}
    rows = box_key(p["POSITION"][:, 0]) - 10
    values = decode_vertex_channels("NORMAL_FRAME", uv)
    assert np.array_equal(values[:, 4], np.array([5, 6, 6, 8, 9])[rows])
    assert np.array_equal(values[:, 5], np.array([3, 4, 4, 5, 6])[rows])  # A's box 5 has depth 2 too
    with pytest.raises(AssertionError):
        assert np.array_equal(values[:, 4], np.array([2, 6, 6, 8, 9])[rows])


def test_linked_duplicates_follow_the_first_and_no_loop_is_written(blender, scene, tmp_path):
    """a (mesh A) under b (mesh B), and linked duplicates b2 (mesh B) under a2 (mesh A), exported
    as [a, b2, b, a2]: each mesh follows its first object (A under B, B under A), which would
    loop; the second link is left out and warned about, and the file's parents form a tree."""
    (a, b), _ = scene
    a2, b2 = (blender.data.objects.new(name, ob.data) for name, ob in (("a2", a), ("b2", b)))
    for ob in (a2, b2):
        blender.context.scene.collection.objects.link(ob)
    a.parent, b2.parent = b, a2
    blender.context.view_layer.update()
    path = tmp_path / "p.glb"
    report = export_scene.export_objects(blender.context, [a, b2, b, a2], "GLTF", str(path), "NORMAL_FRAME")
    assert sum("share the mesh" in w for w in report["warnings"]) == 2
    assert sum("left out" in w for w in report["warnings"]) == 1
    parents = np.full(11, -2)
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        parents[np.rint(p["TEXCOORD_2"][:, 1]).astype(int)] = np.rint(p["TEXCOORD_7"][:, 0]).astype(int)
    assert (parents >= -1).all()
    for box in range(11):  # every chain of parents ends at a root within 11 steps
        steps = 0
        while box >= 0 and steps <= 11:
            box, steps = parents[box], steps + 1
        assert box == -1
    assert report["meshes"][0]["box_parameters"]["object_parent"]["mesh"] == "B"
    assert "object_parent" not in report["meshes"][1]["box_parameters"]

"""Hostile inputs to the export and its files, round 3 (docs/CHECKS.md lists them): linked and
overridden assets, parents left stale by edits after the bake, parameter values no file can hold,
strict JSON, every file writer atomic (also under a real file-size limit), export paths without a
name or extension, one random-seed range, painted parents reported as written, the Godot 3 box
table text."""
import ast
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from boxmarch import cli, cli_args, core, scenes
from boxmarch.formats import glb, godot
from tests.conftest import empty_scene, mesh_object, random_boxes_object
from tests.gltf_reader import read_glb
from tests.helpers.blender_program import module_environment, run_module

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon" / "boxmarch"
SPACING = 1.5  # boxes of side 1 at x = SPACING * key: the key names a box in any file


def parser():
    return cli_args.build_parser("", dict.fromkeys(("bake", "dedup", "merge", "pack-uv", "export", "pipeline",
                                                      "demo")), "boxmarch")


# --- one random-seed range ------------------------------------------------------------------


@pytest.mark.parametrize("seed", ["-1", "2147483648", "4294967295", "4294967296"])
def test_a_random_seed_outside_the_operators_range_is_refused_by_the_command_line(seed):
    with pytest.raises(cli_args.InputError, match=rf"--random-seed: must be in 0\.\.2147483647, got {seed}$"):
        parser().parse_args(["bake", "--random-seed", seed])
    assert parser().parse_args(["bake", "--random-seed", "2147483647"]).random_seed == 2**31 - 1


def test_the_bake_and_its_operator_take_the_same_seed_range(blender):
    from boxmarch import mesh_io

    ob = random_boxes_object(blender, "Seeded")
    props = blender.ops.boxmarch.bake.get_rna_type().properties["random_seed"]
    assert (props.hard_min, props.hard_max) == (0, core.RANDOM_SEED_MAX) == (0, 2**31 - 1)
    for seed in (-1, 2**31, 2**32):
        with pytest.raises(mesh_io.BakeInputError, match=rf"random seed must be a whole number in 0\.\.2147483647, "
                                                         rf"got {seed}"):
            mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings(random_seed=seed))
    assert mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings(random_seed=2**31 - 1)).result.submesh_count == 4


# --- painted parents reported as written ----------------------------------------------------


@pytest.mark.parametrize("parent, written", [(-5, "-5"), (-2**40, "-1099511627776"), (1e10, "10000000000"),
                                             (2**31, "2147483648")])
def test_a_parent_out_of_range_is_named_as_given(parent, written):
    given = np.array([-1, 0, 0, parent], np.float64)
    with pytest.raises(ValueError, match=rf"^box 3 names parent {written}, outside -1\.\.3$"):
        core.box_hierarchy(np.zeros((4, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (4, 1)), np.ones((4, 3)),
                           given_parent=given)


@pytest.mark.parametrize("kind, value, written", [("INT", -5, "-5"), ("FLOAT", -2.0**40, "-1099511627776"),
                                                  ("FLOAT", 1e10, "10000000000"), ("INT", 2**24 + 1, "16777217")])
def test_a_painted_parent_out_of_range_is_reported_as_painted(blender, kind, value, written):
    """An INT attribute keeps every bit through the per-box reduction (float32 would make
    16777217 a 16777216, which names a box in a mesh that large)."""
    from boxmarch import mesh_io

    ob = random_boxes_object(blender, "Painted")
    values = np.full(len(ob.data.vertices), -1)
    values[-8:] = value  # the last box
    ob.data.attributes.new("boxmarch_parent", kind, "POINT").data.foreach_set("value", values)
    with pytest.raises(mesh_io.BakeInputError, match=rf"box 3 names parent {written}, outside -1\.\.3$"):
        mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings())


# --- parameter values no file can hold; strict JSON -----------------------------------------


def test_an_object_property_beyond_float32_is_refused_naming_the_object(blender):
    from boxmarch import mesh_io

    ob = random_boxes_object(blender, "Huge")
    for value in (1e39, -1e39, math.inf, math.nan):
        ob["boxmarch_user"] = value
        with pytest.raises(mesh_io.BakeInputError, match=r"object 'Huge': property 'boxmarch_user' is "):
            mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings())
    ob["boxmarch_user"] = 3.4e38  # within float32
    assert blender.ops.boxmarch.bake() == {"FINISHED"}


def test_a_stored_infinite_parameter_is_not_exported(blender, tmp_path):
    """A bake from before the object-property check stored an infinity (the painted attributes
    were refused already): the export refuses it, writing nothing."""
    from boxmarch.export import scene

    ob = random_boxes_object(blender, "Painted")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    stored = ob.data.attributes[".boxmarch_random_user"]  # the one box layer every bake stores
    pairs = np.zeros(len(ob.data.vertices) * 2, np.float32)
    stored.data.foreach_get("vector", pairs)
    pairs[0] = np.inf
    stored.data.foreach_set("vector", pairs)
    with pytest.raises(scene.ExportInputError, match=r"mesh 'Painted': its stored box parameters \(random\) are not "
                                                     "finite"):
        scene.export_objects(blender.context, [ob], "GODOT3", str(tmp_path / "x.glb"))
    assert os.listdir(tmp_path) == []


def _json_calls():
    """(file, line, call) of every json.dump / json.dumps in the project's own code."""
    for folder in ("addon", "bench", "scripts", "shaders", "engines"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                        and node.func.attr in ("dump", "dumps") and getattr(node.func.value, "id", None) == "json"):
                    yield path.relative_to(ROOT), node.lineno, node


def test_every_json_the_project_writes_is_strict(tmp_path):
    calls = list(_json_calls())
    assert len(calls) >= 10  # the walk finds them: cli, the sidecar, the glb, the benches
    loose = [f"{path}:{line}" for path, line, call in calls
             if not any(k.arg == "allow_nan" and getattr(k.value, "value", None) is False for k in call.keywords)]
    assert loose == []
    # Driven with hostile values, the writers refuse rather than write the tokens, and leave nothing.
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        cli.write_json(str(tmp_path / "r.json"), {"seconds": math.inf})
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        glb.write(str(tmp_path / "m.glb"), {"accessors": [{"min": [math.nan]}]}, b"")
    assert os.listdir(tmp_path) == []


# --- every file writer atomic ---------------------------------------------------------------

# Every function of the add-on that writes a file itself (opens one for writing, or has Blender
# save one), and how it stays atomic: "atomic" (it writes through files.write_atomically or
# write_together) or "body" (it writes the temporary path it is given; each of its callers is
# atomic). A new writer must be added here, and then pass the checks below.
FILE_WRITERS = {
    "blend_file.save_blend_copy": "atomic",
    "cli.write_json": "atomic",
    "demo._preview_picture": "atomic",
    "export/scene._write_sidecar": "body",
    "export/scene.export_objects": "atomic",
    "formats/fbx_container.write": "atomic",
    "formats/files.write_bytes": "body",
    "formats/glb.write": "atomic",
    "formats/godot.write_image_texture_tres": "body",
}
# image.save(), bpy.ops.wm.save_as_mainfile(), bpy.data.libraries.write(), files.write_bytes()
_WRITE_CALLS = {"save": "image", "save_as_mainfile": "bpy.ops.wm", "write": "bpy.data.libraries",
                "write_bytes": "files"}


def _writes_a_file(call) -> bool:
    func = call.func
    if isinstance(func, ast.Name) and func.id == "open":
        mode = call.args[1] if len(call.args) > 1 else next((k.value for k in call.keywords if k.arg == "mode"), None)
        modes = [n.value for n in ast.walk(mode) if isinstance(n, ast.Constant)] if mode is not None else []
        return any(isinstance(m, str) and any(c in m for c in "wax+") for m in modes)
    if isinstance(func, ast.Attribute) and func.attr in _WRITE_CALLS:
        return ast.unparse(func.value) == _WRITE_CALLS[func.attr]
    return False


def _top_level_functions():
    """{"module.function": (ast node, source)} of the add-on's top-level functions."""
    out = {}
    for path in sorted(ADDON.rglob("*.py")):
        module = str(path.relative_to(ADDON).with_suffix(""))
        tree = ast.parse(path.read_text(), str(path))
        for node in tree.body:
            if isinstance(node, ast.FunctionDef):
                out[f"{module}.{node.name}"] = node
    return out


def _calls_atomic(node) -> bool:
    return any(isinstance(n, ast.Attribute) and n.attr in ("write_atomically", "write_together")
               for n in ast.walk(node))


def _callers(functions, name):
    short = name.rsplit(".", 1)[1]
    return [caller for caller, node in functions.items() if caller != name and any(
        isinstance(n, ast.Call) and getattr(n.func, "attr", getattr(n.func, "id", None)) == short
        for n in ast.walk(node))]


def _only_reached_atomically(functions, name, seen=()) -> bool:
    """``name`` writes through write_atomically/write_together, or every function calling it
    does (through any chain of callers)."""
    if _calls_atomic(functions[name]):
        return True
    callers = _callers(functions, name)
    return bool(callers) and all(caller not in seen and _only_reached_atomically(functions, caller, (*seen, name))
                                 for caller in callers)


def test_every_file_writer_is_listed_and_atomic():
    functions = _top_level_functions()
    writers = {name for name, node in functions.items()
               if any(isinstance(n, ast.Call) and _writes_a_file(n) for n in ast.walk(node))}
    assert writers == set(FILE_WRITERS)
    for name, how in FILE_WRITERS.items():
        assert _calls_atomic(functions[name]) == (how == "atomic"), name
        assert _only_reached_atomically(functions, name), name


def run_every_writer(tmp_path, mode):
    """tests/hostile/every_writer_child.py's results in ``mode`` ("limit" or "links"), having
    checked that they cover each writer a caller reaches."""
    folder = tmp_path / "out"
    folder.mkdir()
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "hostile" / "every_writer_child.py"), mode, str(folder)],
                       env=module_environment(tmp_path), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    results = json.loads(r.stdout.strip().splitlines()[-1])
    atomic = {name.replace("/", ".") for name, how in FILE_WRITERS.items() if how == "atomic"}
    # the demo's picture is left out (the demo runs in tests/test_cli.py); the FBX frame patch
    # writes through fbx_container.write, and is run too
    assert {name.split()[0] for name in results} == atomic - {"demo._preview_picture"} | {"formats.fbx.replace_frame"}
    return results


@pytest.mark.slow
def test_every_writer_under_a_file_size_limit_leaves_the_earlier_files(tmp_path):
    """Each writer a caller reaches, under RLIMIT_FSIZE (a full disk stops a write the same way):
    each fails, and every file is as it was, none added."""
    for name, result in run_every_writer(tmp_path, "limit").items():
        assert result["error"] is not None, name  # the limit was reached...
        assert (result["changed"], result["added"]) == ([], []), (name, result)  # ...and nothing is left of it


@pytest.mark.slow
def test_every_writer_writes_through_a_symbolic_link(tmp_path):
    """Each writer a caller reaches, every file it writes a relative symbolic link to a file in
    another folder: each link is kept, pointing where it did, and every target is replaced by
    the new file, nothing added. Before: the link was replaced by a regular file, its target left
    as it was."""
    for name, result in run_every_writer(tmp_path, "links").items():
        linked = result["earlier"] + ["cube.fbx"]  # the FBX frame patch's own file, linked throughout
        assert result["error"] is None, (name, result)
        assert result["links"] == {n: f"targets/{n}" for n in linked}, (name, result)
        changed = {f"targets/{n}" for n in result["earlier"]} | ({"targets/cube.fbx"} if "replace_frame" in name else set())
        assert set(result["changed"]) == changed and result["added"] == [], (name, result)


# --- export paths ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", [".glb", "model", "model.fbx", "sub/.glb"])
def test_an_export_path_without_a_name_or_the_extension_writes_nothing(blender, tmp_path, name):
    from boxmarch.export import scene

    ob = random_boxes_object(blender, "Boxes")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    (tmp_path / "sub").mkdir()
    with pytest.raises(scene.ExportInputError, match=r"no file name before \.glb|must end in \.glb"):
        scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / name))
    assert sorted(os.listdir(tmp_path)) == ["sub"] and os.listdir(tmp_path / "sub") == []


@pytest.mark.slow
def test_the_command_line_refuses_a_to_without_a_name(baked_blend, tmp_path):
    r = run_module(["export", str(baked_blend), "--to", ".glb"], tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().splitlines()[-1] == ("boxmarch: error: --to: '.glb' has no file name before .glb: "
                                                 "name the file, e.g. 'model.glb'")
    assert os.listdir(tmp_path) == ["world.blend"]


# --- linked and overridden assets -----------------------------------------------------------


def _library(bpy, tmp_path):
    """lib.blend: four random boxes, baked; and reference.glb, exported from that file itself.
    Leaves an empty scene."""
    ob = random_boxes_object(bpy, "Baked")
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    from boxmarch.export import scene

    scene.export_objects(bpy.context, [ob], "GLTF", str(tmp_path / "reference.glb"))
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "lib.blend"))
    empty_scene(bpy)
    return tmp_path / "lib.blend"


def _link(bpy, library, how):
    with bpy.data.libraries.load(str(library), link=True) as (_src, dst):
        dst.objects = ["Baked"]
    ob = dst.objects[0]
    bpy.context.scene.collection.objects.link(ob)
    if how == "mesh":  # a local object using the linked mesh
        ob = bpy.data.objects.new("Local", ob.data)
        bpy.context.scene.collection.objects.link(ob)
    elif how == "override":
        ob = ob.override_create(remap_local_usages=True)
    return ob


@pytest.mark.parametrize("how", ["object", "mesh", "override"])
def test_a_linked_or_overridden_baked_asset_exports_as_the_library_itself_does(blender, tmp_path, how):
    from boxmarch.export import scene

    library = _library(blender, tmp_path)
    ob = _link(blender, library, how)
    assert ob.data.library is not None
    meshes = len(blender.data.meshes)
    for preset, name in (("GLTF", "linked.glb"), ("UNITY", "linked.fbx"), ("GODOT3", "godot.glb")):
        report = scene.export_objects(blender.context, [ob], preset, str(tmp_path / name))
        assert report["stale_boxes"] == 0 and report["transform_error"] < 1e-5, report
        assert len(blender.data.meshes) == meshes and ob.data.library is not None  # no copy left, data put back
    (linked,), (reference,) = read_glb(tmp_path / "linked.glb"), read_glb(tmp_path / "reference.glb")
    assert linked["name"] == reference["name"] == "Baked"
    for attribute, values in reference["primitives"][0].items():
        assert np.array_equal(linked["primitives"][0][attribute], values), attribute
    # An exporter that fails leaves no copy behind either.
    real = scene.run_exporter
    scene.run_exporter = lambda *_args: (_ for _ in ()).throw(RuntimeError("the exporter failed"))
    try:
        with pytest.raises(RuntimeError, match="the exporter failed"):
            scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "failed.glb"))
    finally:
        scene.run_exporter = real
    assert len(blender.data.meshes) == meshes and not (tmp_path / "failed.glb").exists()


def test_a_local_mesh_named_as_a_linked_one_exports_beside_it(blender, tmp_path):
    """Two meshes called Baked, one linked, one local: both reach the file, each with its own boxes."""
    from boxmarch.export import scene

    ob = _link(blender, _library(blender, tmp_path), "object")
    local = random_boxes_object(blender, "Baked", count=2, offset=20.0)
    assert local.data.name == "Baked" and local.data.library is None
    for other in blender.context.selected_objects:
        other.select_set(other == local)
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    report = scene.export_objects(blender.context, [ob, local], "GLTF", str(tmp_path / "both.glb"))
    assert [m["boxes"] for m in report["meshes"]] == [4, 2] and report["transform_error"] < 1e-5
    assert sorted(mesh["name"] for mesh in read_glb(tmp_path / "both.glb")) == ["Baked", "Baked.001"]
    assert local.data.name == "Baked" and ob.data.name == "Baked"


# --- stale parents --------------------------------------------------------------------------


def _row(blender, name, keys):
    centres = np.stack([SPACING * np.asarray(keys, float), np.zeros(len(keys)), np.zeros(len(keys))], 1)
    return mesh_object(blender, name, *scenes.box_arrays(centres, 1.0, np.eye(3)), select=True)


def _file_parents(path):
    """{box key: (file index, parent, depth)} from a GLTF NORMAL_FRAME file (TEXCOORD_2's second
    component the box number, TEXCOORD_7 = (parent, depth): docs/FORMAT.md)."""
    out = {}
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        keys = np.rint(p["POSITION"][:, 0] / SPACING).astype(int)
        rows = np.stack([np.rint(p["TEXCOORD_2"][:, 1]), p["TEXCOORD_7"][:, 0], p["TEXCOORD_7"][:, 1]], 1)
        for key, row in zip(keys, rows.astype(int)):
            assert out.setdefault(int(key), tuple(row)) == tuple(row)  # one value per box
    return out


def _export_parents(blender, tmp_path, objects):
    from boxmarch.export import scene

    path = tmp_path / "p.glb"
    report = scene.export_objects(blender.context, objects, "GLTF", str(path), "NORMAL_FRAME")
    return report, _file_parents(path)


def _delete_box(mesh, key):
    import bmesh

    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if abs(v.co.x - SPACING * key) < 0.6], context="VERTS")
    bm.to_mesh(mesh)
    bm.free()


def test_deleting_a_box_of_a_baked_chain_keeps_the_others_parents(blender, tmp_path):
    """Boxes at keys 0..5, CHAIN: box k's parent is box k - 1. Box 2 deleted, no bake since: the
    boxes after it are numbered one lower, their stored parents name the old numbers. Box 3 lost
    its parent (a root now, warned about), 4 and 5 keep theirs under the new numbers."""
    ob = _row(blender, "Chain", range(6))
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    _delete_box(ob.data, 2)
    report, boxes = _export_parents(blender, tmp_path, [ob])
    index = {key: row[0] for key, row in boxes.items()}
    assert sorted(boxes) == [0, 1, 3, 4, 5]
    want = {0: (-1, 0), 1: (index[0], 1), 3: (-1, 0), 4: (index[3], 1), 5: (index[4], 2)}
    assert {key: row[1:] for key, row in boxes.items()} == want
    assert report["stale_parents"] == 1 and report["stale_boxes"] == 0
    assert any("1 of 5 boxes name parents that no box holds since the bake" in w for w in report["warnings"])


def test_a_bake_without_box_numbers_writes_no_self_parent_after_a_deletion(blender, tmp_path):
    """A bake that stored no box numbers (.boxmarch_box, before they were stored): the deletion
    above leaves boxes naming themselves, found by their stored depths; they become roots."""
    ob = _row(blender, "Chain", range(6))
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    numbers = ob.data.attributes.get(".boxmarch_box")
    if numbers is not None:
        ob.data.attributes.remove(numbers)
    _delete_box(ob.data, 2)
    report, boxes = _export_parents(blender, tmp_path, [ob])
    assert {key: row[1:] for key, row in boxes.items()} == {0: (-1, 0), 1: (boxes[0][0], 1), 3: (-1, 0),
                                                            4: (-1, 0), 5: (-1, 0)}
    assert report["stale_parents"] == 3


def test_a_bake_without_box_numbers_drops_a_parent_its_stored_depths_disagree_with(blender, tmp_path):
    """Boxes 2 and 3 of the chain deleted, no box numbers stored: box 4, numbered 2 now, stores
    parent 3 (box 5's number now), which is in range and not itself; only the stored depths (4
    under a parent of depth 5) tell the parent is stale. Box 5 stores parent 4, out of range."""
    ob = _row(blender, "Chain", range(6))
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    ob.data.attributes.remove(ob.data.attributes[".boxmarch_box"])
    _delete_box(ob.data, 2)
    _delete_box(ob.data, 3)
    report, boxes = _export_parents(blender, tmp_path, [ob])
    assert {key: row[1:] for key, row in boxes.items()} == {0: (-1, 0), 1: (boxes[0][0], 1), 4: (-1, 0), 5: (-1, 0)}
    assert report["stale_parents"] == 2


def test_removing_a_duplicate_box_after_a_chain_bake_keeps_every_parent(blender, tmp_path):
    """Keys 0, 1, 1, 2, 3 (box 2 a copy of box 1), CHAIN; Delete Duplicate Submeshes removes one
    copy without a re-bake: the boxes after it keep their parents under the new numbers."""
    ob = _row(blender, "Chain", [0, 1, 1, 2, 3])
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    assert blender.ops.boxmarch.dedup_submeshes() == {"FINISHED"}
    report, boxes = _export_parents(blender, tmp_path, [ob])
    index = {key: row[0] for key, row in boxes.items()}
    assert {key: row[1:] for key, row in boxes.items()} == {0: (-1, 0), 1: (index[0], 1), 2: (index[1], 2),
                                                            3: (index[2], 3)}
    assert report["stale_parents"] == 0 and not any("parents" in w for w in report["warnings"])


def test_joining_two_baked_objects_writes_no_parent_of_the_other_mesh(blender, tmp_path):
    a = _row(blender, "A", [0, 1, 2])
    _row(blender, "B", [10, 11, 12])
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    blender.context.view_layer.objects.active = a
    assert blender.ops.object.join() == {"FINISHED"}
    assert "B" not in blender.data.objects
    report, boxes = _export_parents(blender, tmp_path, [a])
    assert sorted(boxes) == [0, 1, 2, 10, 11, 12]
    # Both meshes' boxes 1 and 2 name "box 0" and "box 1", which two boxes hold now: none is kept.
    assert all(row[1:] == (-1, 0) for row in boxes.values()), boxes
    assert report["stale_parents"] == 4


def test_a_stored_parent_out_of_range_is_never_written(blender, tmp_path):
    """The second mesh's boxes number from 2 in the file: a stored parent 99 was written as 101."""
    first = _row(blender, "First", [20, 21])
    ob = _row(blender, "Chain", range(4))
    assert blender.ops.boxmarch.bake(hierarchy="CHAIN") == {"FINISHED"}
    layer = ob.data.attributes[".boxmarch_parent"]
    stored = np.empty(len(ob.data.vertices), np.int32)
    layer.data.foreach_get("value", stored)
    stored[24:32] = 99  # box 3
    layer.data.foreach_set("value", stored)
    report, boxes = _export_parents(blender, tmp_path, [first, ob])
    parents = {key: row[1] for key, row in boxes.items()}
    assert parents == {20: -1, 21: 0, 0: -1, 1: 2, 2: 3, 3: -1}
    assert report["meshes"][1]["stale_parents"] == 1
    # Every box reaches a root: no box is its own parent or ancestor.
    up = {row[0]: row[1] for row in boxes.values()}
    for box in up:
        for _ in range(len(up)):
            box = up[box]
            if box < 0:
                break
        assert box < 0


# --- the Godot 3 box table as text ----------------------------------------------------------


@pytest.mark.parametrize("boxes", [1, 3, 700])
def test_the_godot3_table_text_lists_every_byte(tmp_path, monkeypatch, boxes):
    """The streamed text holds the image's bytes as ", ".join(map(str, bytes)) would, across
    chunk boundaries (a chunk of 7 bytes here), with the header and footer Godot 3 reads."""
    table = np.random.default_rng(boxes).standard_normal((boxes, 5, 4)).astype(np.float32)
    table.view(np.uint32)[0, 0] = [0, 0xFFFFFFFF, 0x0A0B0C0D, 0x64C80901]  # 0, 255, 1-3 digit bytes
    monkeypatch.setattr(godot, "TEXT_CHUNK_BYTES", 7)
    godot.write_image_texture_tres(tmp_path / "t.tres", table)
    image = godot.table_image(table)
    height, width = image.shape[:2]
    data = ", ".join(str(b) for b in image.astype("<f4").tobytes())
    assert (tmp_path / "t.tres").read_text() == (
        '[gd_resource type="ImageTexture" load_steps=2 format=2]\n\n[sub_resource type="Image" id=1]\n'
        f'data = {{\n"data": PoolByteArray( {data} ),\n"format": "RGBAFloat",\n"height": {height},\n'
        f'"mipmaps": false,\n"width": {width}\n}}\n\n'
        f'[resource]\nflags = 0\nimage = SubResource( 1 )\nsize = Vector2( {width}, {height} )\n')

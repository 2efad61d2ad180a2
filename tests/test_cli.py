"""The command line in both forms: `python -m boxmarch` (a Python with bpy) and Debian's Blender
3.4 program (`blender --background FILE --python-expr "import boxmarch.cli; boxmarch.cli.main()"
-- ...`). Exit codes, reports, outputs that appear only complete, and decodes of what it wrote."""
import hashlib
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from boxmarch import scenes
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb
from tests.helpers.blender_program import SCRIPTS, blender_env, run_module

pytestmark = pytest.mark.slow  # python -m boxmarch and Blender 3.4 program subprocesses

TO_GLTF = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
COUNT, SEED = 60, 11


def boxes_reference():
    """Centres and half-extents of the boxes make_boxes.py writes (same seed, same generator)."""
    (positions, *_), centres, sizes, _ = scenes.random_boxes(COUNT, seed=SEED, spread=10.0, size_range=(0.5, 3.0))
    return positions, centres, sizes.max(axis=1) / 2


def run_blender_cli(blend, args, package_parent, cwd, timeout=240):
    home = Path(cwd).parent / f"{Path(cwd).name}-home"
    home.mkdir(exist_ok=True)
    env = blender_env(home)
    env["PYTHONPATH"] = str(package_parent)  # Debian's Blender honours it
    command = [shutil.which("blender"), "--background", "--factory-startup"]
    if blend:
        command.append(str(blend))
    command += ["--python-expr", "import boxmarch.cli; boxmarch.cli.main()", "--", *args]
    return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def boxes_blend_34(package_parent, tmp_path_factory):
    """An unbaked boxes file saved by Blender 3.4 (5.0's files do not open in 3.4; 3.4's open in both)."""
    folder = tmp_path_factory.mktemp("input")
    path = folder / "boxes.blend"
    proc = subprocess.run([shutil.which("blender"), "--background", "--factory-startup", "--python-exit-code", "1",
                           "--python", str(SCRIPTS / "make_boxes.py"), "--", str(package_parent), str(path),
                           str(COUNT), str(SEED)], env=blender_env(folder), capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0 and path.exists(), proc.stdout[-2000:] + proc.stderr[-2000:]
    return path


@pytest.fixture(scope="module")
def messy_blend_34(package_parent, tmp_path_factory):
    """Like boxes_blend_34, plus the object "Messy" (duplicates and a split corner)."""
    folder = tmp_path_factory.mktemp("messy")
    path = folder / "messy.blend"
    proc = subprocess.run([shutil.which("blender"), "--background", "--factory-startup", "--python-exit-code", "1",
                           "--python", str(SCRIPTS / "make_boxes.py"), "--", str(package_parent), str(path),
                           str(COUNT), str(SEED), "MESSY"], env=blender_env(folder), capture_output=True, text=True,
                          timeout=240)
    assert proc.returncode == 0 and path.exists(), proc.stdout[-2000:] + proc.stderr[-2000:]
    return path


def digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def assert_glb_decodes_to_centres(path, tolerance=1e-5):
    positions, centres, half = boxes_reference()
    lookup = {tuple(r): i for i, r in enumerate((positions.astype(np.float64) @ TO_GLTF.T).astype(np.float32).tolist())}
    worst = 0.0
    for primitive in read_glb(path)[0]["primitives"]:
        box = np.array([lookup[tuple(r)] for r in primitive["POSITION"].astype(np.float32).tolist()]) // 8
        if "TANGENT" in primitive:  # NORMAL_FRAME (docs/ENGINES.md): x = tangent, z = normal
            t, z = primitive["TANGENT"], primitive["NORMAL"]
            f = np.concatenate([primitive["TEXCOORD_1"], primitive["TEXCOORD_2"][:, :1]], axis=1)
            y = np.cross(z, t[:, :3]) * t[:, 3:4]
            origin = primitive["POSITION"] + t[:, :3] * f[:, :1] + y * f[:, 1:2] + z * f[:, 2:3]
        else:  # CLASSIC (docs/FORMAT.md)
            c = primitive["COLOR_0"]
            q = np.concatenate([primitive["TEXCOORD_1"], primitive["TEXCOORD_2"]], axis=1)
            f = (c[:, :3] * 2 - 1) / c[:, 3:4]
            u, w = q[:, :3], q[:, 3:4]
            origin = primitive["POSITION"] + f + 2 * np.cross(u, np.cross(u, f) + w * f)
        worst = max(worst, float((np.linalg.norm(origin - centres[box] @ TO_GLTF.T, axis=1) / half[box]).max()))
    assert worst <= tolerance, worst
    return worst


# --- python -m boxmarch -------------------------------------------------------------------------


@pytest.mark.bpy
@pytest.mark.parametrize("renderer", ["AUTO", "CPU"])
def test_module_demo_prints_table_and_writes_checked_files(tmp_path, renderer):
    proc = run_module(["demo", "--count", "300", "--out", "out", "--json", "demo.json", "--preview", renderer], tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for step in ("build scene", "dedup", "merge", "bake BYTE_COLOR", "bake FLOAT_COLOR", "re-bake (incremental)",
                 "pack-uv", "export demo.glb (GLTF)", "preview demo.png", "total"):
        assert f"| {step} " in proc.stdout, step
    assert "[boxmarch]" in proc.stderr  # progress goes to stderr
    # No warning of Blender's passed on: the glTF exporter's "Armature must be the parent of
    # skinned mesh" is gone with the character parented to its rig.
    assert "[boxmarch] Blender:" not in proc.stderr, proc.stderr
    # stdout is the table alone: Blender's exporter and save lines (naming temporary files) are held back
    assert proc.stdout.startswith("boxmarch demo:") and "boxmarch-partial" not in proc.stdout + proc.stderr
    assert max(map(len, proc.stdout.splitlines())) <= 100, proc.stdout  # fits a terminal
    # The demo wrote demo_godot3.glb.import, which keeps Godot 3's import float32
    assert "float32 in Godot 3" in next(line for line in proc.stdout.splitlines() if "| export GODOT3" in line)
    # 300 boxes + 6 split-corner vertices: 6 planted duplicates (48 vertices) and the 6 splits go away
    assert "2,406 -> 2,358 pebble vertices" in proc.stdout and "2,358 -> 2,352 pebble vertices" in proc.stdout
    report = json.loads((tmp_path / "demo.json").read_text())
    assert report["ok"] and report["count"] == 300 and report["glb_max_relative_error"] < 1e-5
    if renderer == "CPU":
        assert report["preview"] == "CPU reference raymarcher"
    else:  # no EGL complaints of Blender's while making the GPU context that then worked
        assert report["preview"] != "GPU raymarch preview" or "EGL Error" not in proc.stderr, proc.stderr
    meshes = read_glb(tmp_path / "out" / "demo.glb")
    assert sorted(m["name"] for m in meshes) == ["Chains", "Mannequin", "Pebbles"]
    assert sorted(os.listdir(tmp_path / "out")) == sorted([
        "demo.blend", "demo.glb", "demo.boxes.bin", "demo.png", "demo_godot3.glb", "demo_godot3.boxes.tres",
        "demo_unity.fbx", "demo_unity.boxes.bin", "demo_unreal.fbx", "demo_unreal.boxes.bin",
        "demo_godot3.glb.import"]  # demo.glb is the GLTF preset's file
        + [f"demo{suffix}.boxmarch.json" for suffix in ("", "_godot3", "_unity", "_unreal")])
    for preset, layout in (("demo.glb \\(GLTF\\)", "NORMAL_FRAME"), ("GODOT3", "NORMAL_COLOR"), ("UNITY", "NORMAL_FRAME"),
                           ("UNREAL", "UV_FRAME")):
        assert re.search(rf"export {preset} .*layout {layout}", proc.stdout), proc.stdout
    png = (tmp_path / "out" / "demo.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and int.from_bytes(png[16:20], "big") == 800


@pytest.mark.bpy
def test_module_bake_export_pipeline_on_a_file(boxes_blend_34, tmp_path):
    source = tmp_path / "in.blend"
    shutil.copy(boxes_blend_34, source)
    before = digest(source)
    proc = run_module(["pipeline", str(source), "--objects", "Boxes", "--steps", "bake,export", "--preset", "GLTF",
                       "--to", "boxes.glb", "--out", "baked.blend", "--json", "report.json"], tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads((tmp_path / "report.json").read_text())
    bake, export = report["steps"]
    assert (bake["step"], bake["baked"], bake["submeshes"]) == ("bake", COUNT, COUNT)
    assert bake["max_relative_error"] < 1e-5
    assert export["preset"] == "GLTF" and export["meshes"][0]["uv_channels"] == [1, 2, 3, 4, 5, 6, 7]
    assert digest(source) == before  # the input is never written
    assert_glb_decodes_to_centres(tmp_path / "boxes.glb")
    # The written .blend holds the bake: export from it alone gives the same file content.
    proc = run_module(["export", "baked.blend", "--preset", "UNITY", "--to", "boxes.fbx"], tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "boxes.fbx").stat().st_size > 0
    # The result table (its import note the longest cell) fits a terminal; the default import's
    # cost is that note, not a warning.
    assert max(map(len, proc.stdout.splitlines())) <= 100 and "half-float" in proc.stdout, proc.stdout
    assert "[boxmarch] WARNING:" not in proc.stderr, proc.stderr


@pytest.mark.bpy
def test_module_cleanup_pipeline_dedups_merges_bakes_and_packs(messy_blend_34, tmp_path, blender):
    proc = run_module(["pipeline", str(messy_blend_34), "--objects", "Messy", "--steps", "dedup,merge,bake,pack-uv",
                       "--tolerance", "1e-4", "--distance", "1e-3", "--padding", "0.01",
                       "--out", "clean.blend", "--json", "report.json"], tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    steps = {s["step"]: s for s in json.loads((tmp_path / "report.json").read_text())["steps"]}
    # 13 boxes of 8 vertices + 1 split corner; dedup drops the 3 duplicates, merge the split corner.
    assert (steps["dedup"]["before"]["vertices"], steps["dedup"]["after"]["vertices"]) == (105, 81)
    assert (steps["merge"]["before"]["vertices"], steps["merge"]["after"]["vertices"]) == (81, 80)
    assert steps["bake"]["submeshes"] == 10 and steps["bake"]["max_relative_error"] < 1e-5
    with blender.data.libraries.load(str(tmp_path / "clean.blend")) as (src, dst):
        dst.meshes = ["Messy"]
    mesh = dst.meshes[0]
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers["UVMap"].data.foreach_get("uv", uv)
    assert len(mesh.vertices) == 80 and uv.min() >= 0.0 and uv.max() <= 1.0 and np.ptp(uv) > 0.5


@pytest.mark.bpy
@pytest.mark.parametrize("args, reason", [
    (["bake", "missing.blend"], "no such file"),
    (["bake", "notes.txt"], "not a .blend file"),
    (["bake", "in.blend", "--objects", "Nope"], "no object named 'Nope'"),
    (["bake", "in.blend", "--objects", "Camera"], "is a camera, not a mesh"),
    (["bake", "in.blend", "--encoding", "HALF"], "invalid choice"),
    (["bake", "in.blend", "--out", "nowhere/x.blend"], "does not exist"),
    (["bake", "in.blend", "--out", "x.txt"], "must name a .blend"),
    (["export", "in.blend", "--preset", "GLTF"], "--to"),
    (["export", "in.blend", "--preset", "GLTF", "--to", "x.glb"], "not baked"),
    (["export", "in.blend", "--preset", "GODOT3", "--to", "in.blend.glb"], "is a folder"),
    (["pipeline", "in.blend", "--steps", "bake,polish"], "--steps"),
    (["demo", "--count", "0"], "--count must be in 100.."),
    (["frobnicate"], "invalid choice"),
])
def test_module_bad_input_exits_2_with_one_line_and_writes_nothing(boxes_blend_34, tmp_path, args, reason):
    shutil.copy(boxes_blend_34, tmp_path / "in.blend")
    (tmp_path / "notes.txt").write_text("not a blend file")
    (tmp_path / "in.blend.glb.import").mkdir()  # where a GODOT3 export to in.blend.glb writes its import settings
    files_before = sorted(os.listdir(tmp_path))
    proc = run_module(args, tmp_path)
    assert proc.returncode == 2, proc.stdout[-2000:] + proc.stderr[-2000:]
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("boxmarch: error:") and reason in last, proc.stderr
    assert sorted(os.listdir(tmp_path)) == files_before


def test_module_export_refuses_a_report_over_its_sidecar(boxes_blend_34, tmp_path):
    """The sidecar written beside --to is an output: --json naming it is refused before anything
    is exported, and the refused --json is not written either (the error goes to stderr)."""
    shutil.copy(boxes_blend_34, tmp_path / "in.blend")
    proc = run_module(["pipeline", "in.blend", "--steps", "bake,export", "--preset", "GLTF", "--to", "x.glb",
                       "--json", "x.boxmarch.json"], tmp_path)
    assert proc.returncode == 2
    assert ("--json 'x.boxmarch.json' and the export beside --to 'x.boxmarch.json' name the same file"
            in proc.stderr.strip().splitlines()[-1])
    assert sorted(os.listdir(tmp_path)) == ["in.blend"]


@pytest.mark.bpy
def test_module_failure_report_is_json_when_asked(boxes_blend_34, tmp_path):
    shutil.copy(boxes_blend_34, tmp_path / "in.blend")
    proc = run_module(["bake", "in.blend", "--objects", "Camera", "--out", "o.blend", "--json", "r.json"], tmp_path)
    assert proc.returncode == 2
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["ok"] is False and report["exit_code"] == 2 and "camera" in report["error"]
    assert not (tmp_path / "o.blend").exists()


# --- blender --background FILE --python-expr ... -- ---------------------------------------------


@pytest.mark.blender_program
def test_blender_34_form_bake_export_and_exit_codes(boxes_blend_34, package_parent, tmp_path, blender):  # noqa: F811
    proc = run_blender_cli(boxes_blend_34, ["bake", "--out", str(tmp_path / "baked.blend"),
                                            "--json", str(tmp_path / "bake.json")], package_parent, tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    report = json.loads((tmp_path / "bake.json").read_text())
    assert report["blender"].startswith("3.4") and report["objects"] == ["Boxes"]
    assert report["steps"][0]["baked"] == COUNT
    proc = run_blender_cli(tmp_path / "baked.blend", ["export", "--preset", "GLTF", "--to", str(tmp_path / "b.glb")],
                           package_parent, tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert_glb_decodes_to_centres(tmp_path / "b.glb")
    # 3.4's FBX exporter: the raw file decodes in Unity's frame (x negated) onto the centres.
    proc = run_blender_cli(tmp_path / "baked.blend", ["export", "--preset", "UNITY", "--layout", "CLASSIC",
                                                      "--to", str(tmp_path / "b.fbx")], package_parent, tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    raw = read_fbx_geometry(tmp_path / "b.fbx")
    _positions, centres, half = boxes_reference()
    c, q = raw["BoxOffset"], np.concatenate([raw["BoxQuatXY"], raw["BoxQuatZW"]], axis=1)
    f = (c[:, :3] * 2 - 1) / c[:, 3:4]
    u, w = q[:, :3], q[:, 3:4]
    origin = raw["position"] * [-1, 1, 1] + f + 2 * np.cross(u, np.cross(u, f) + w * f)
    box = raw["vertex"] // 8
    to_unity = TO_GLTF * np.array([-1.0, 1.0, 1.0])[:, None]
    assert (np.linalg.norm(origin - centres[box] @ to_unity.T, axis=1) / half[box]).max() < 1e-5
    proc = run_blender_cli(boxes_blend_34, ["bake", "--objects", "Camera", "--out", str(tmp_path / "no.blend")],
                           package_parent, tmp_path)
    assert proc.returncode == 2 and "is a camera, not a mesh" in proc.stderr
    assert not (tmp_path / "no.blend").exists()
    proc = run_blender_cli(boxes_blend_34, ["bake", "--angle-epsilon", "wide"], package_parent, tmp_path)
    assert proc.returncode == 2 and "invalid float value" in proc.stderr
    # A file handed to boxmarch rather than to Blender is checked (Blender itself exits 0 on an
    # unreadable file without running the script).
    proc = run_blender_cli(None, ["bake", str(tmp_path / "missing.blend")], package_parent, tmp_path)
    assert proc.returncode == 2 and "no such file" in proc.stderr


@pytest.mark.blender_program
def test_blender_34_form_demo(package_parent, tmp_path):  # noqa: F811
    proc = run_blender_cli(None, ["demo", "--count", "300", "--out", str(tmp_path), "--json", str(tmp_path / "r.json")],
                           package_parent, tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "Blender 3.4" in proc.stdout and "| export demo.glb" in proc.stdout and "| pack-uv" in proc.stdout
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["glb_max_relative_error"] < 1e-5
    for name in ("demo.blend", "demo.glb", "demo.png"):
        assert (tmp_path / name).exists()


@pytest.mark.blender_program
def test_blender_34_form_cleanup_commands(messy_blend_34, package_parent, tmp_path):  # noqa: F811
    for command, option, before, after in (("dedup", ["--tolerance", "1e-4"], 105, 81),
                                           ("merge", ["--distance", "1e-3"], 105, 104)):
        proc = run_blender_cli(messy_blend_34, [command, "--objects", "Messy", *option, "--json",
                                                str(tmp_path / f"{command}.json")], package_parent, tmp_path)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        step = json.loads((tmp_path / f"{command}.json").read_text())["steps"][0]
        assert (step["before"]["vertices"], step["after"]["vertices"]) == (before, after)


def test_internal_error_exits_1_with_one_line(monkeypatch, capsys):
    from boxmarch import cli

    def broken(_args):
        raise KeyError("something the code did not expect")

    monkeypatch.setattr(cli, "cmd_bake", broken)
    assert cli.run(["bake"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("boxmarch: internal error: KeyError")

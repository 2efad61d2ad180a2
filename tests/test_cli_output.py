"""What the command line prints in a terminal: tables that fit TABLE_WIDTH columns, --version,
--help with every default, a missing bpy module or native build named as what to install or build
(their own exit code) rather than an internal error, and a command given no .blend refused rather
than run on Blender's startup scene."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from boxmarch import bl_info, cli, cli_args
from tests.conftest import random_boxes_object

COMMANDS = ("bake", "dedup", "merge", "pack-uv", "export", "pipeline", "demo")
REQUIRED = {"export": ["--to", "x.glb"]}  # what each command needs to parse


def test_table_fits_the_width_and_keeps_every_word():
    long = "demo_godot3.glb + demo_godot3.boxmarch.json + demo_godot3.boxes.tres + demo_godot3.glb.import"
    rows = [["export GODOT3", "2.783 s", f"layout NORMAL_COLOR: {long}", "x" * 150],
            ["total", "16.612 s", "wrote /a/rather/long/path/to/demo_out/demo.blend", ""]]
    table = cli.format_table(["step", "time", "what", "accuracy"], rows)
    lines = table.splitlines()
    assert max(map(len, lines)) <= cli.TABLE_WIDTH, table
    assert len({len(line) for line in lines}) == 1  # every line ends at the same column
    # Reading a column top to bottom gives its cells back: nothing cut, nothing reordered.
    columns = [[cell.strip() for cell in line.strip("|").split(" | ")] for line in lines if not line.startswith("|-")]
    what = " ".join(cells[2] for cells in columns[1:] if cells[2]).replace("/ ", "/")  # a path breaks after a '/'
    assert f"layout NORMAL_COLOR: {long}" in what and "wrote /a/rather/long/path" in what
    assert "".join(cells[3] for cells in columns[1:]) == "x" * 150
    assert " ".join(cells[0] for cells in columns if cells[0]) == "step export GODOT3 total"
    # A table that fits is left as it is.
    narrow = cli.format_table(["step", "time"], [["bake", "0.1 s"]])
    assert narrow.splitlines() == ["| step | time  |", "|------|-------|", "| bake | 0.1 s |"]


def test_table_breaks_cells_between_words_only():
    """The demo's rows (issue 37: 'e | ngines/unreal/...'): each column read top to bottom gives
    its cells' words back whole, a line breaking only between words or after a path's '/'."""
    from boxmarch.formats import presets

    rows = [[f"export {name}", "0.812 s", f"layout {preset.layouts[0]}: demo_{name.lower()}.fbx + "
             f"demo_{name.lower()}.boxmarch.json + demo_{name.lower()}.boxes.bin",
             f"default import loses 4.9e-04 of half-extent: {preset.import_fix}"]
            for name, preset in presets.PRESETS.items() if preset.import_fix]
    assert any("engines/unreal/" in row[3] for row in rows)  # the word that was cut
    rows.append(["total", "63.463 s", "wrote /home/someone/projects/a-rather-long-folder-name/demo_out/demo.blend", ""])
    for width in (100, 90):
        table = cli.format_table(["step", "time", "what", "accuracy"], rows, width=width)
        lines = [line for line in table.splitlines()[2:]]
        assert max(map(len, lines)) <= width, table
        for column in range(4):
            read = " ".join(line.strip("|").split(" | ")[column].strip() for line in lines).replace("/ ", "/")
            assert read.split() == " ".join(row[column] for row in rows).split(), (column, table)
    narrow = cli.format_table(["step", "what"], [["total", "wrote /home/someone/a-rather-long-folder-name/x.blend"]], width=40)
    pieces = [line.strip("|").split(" | ")[1].strip() for line in narrow.splitlines()[2:]]
    assert pieces == ["wrote /home/someone/", "a-rather-long-folder-name/", "x.blend"], narrow


def test_version_prints_the_add_on_version(capsys):
    assert cli.run(["--version"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"boxmarch {'.'.join(map(str, bl_info['version']))}"), out


@pytest.mark.parametrize("argv", [["bake", "missing.blend"], ["demo", "--count", "100"]])
def test_missing_bpy_says_what_to_install(monkeypatch, capsys, tmp_path, argv):
    monkeypatch.setitem(sys.modules, "bpy", None)  # `import bpy` raises ModuleNotFoundError, as without bpy
    monkeypatch.chdir(tmp_path)
    assert cli.run(argv) == cli.EXIT_MISSING_MODULE == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no bpy module" in err[0] and "pip install bpy==5.0" in err[0], err
    assert list(tmp_path.iterdir()) == []


def test_the_commands_are_those_the_tests_know(capsys):
    assert cli.run(["--help"]) == 0
    assert "{" + ",".join(COMMANDS) + "}" in capsys.readouterr().out


def option_help(text, option):
    """The help of ``option`` in a --help text, on one line."""
    found = re.search(rf"^  {re.escape(option)}\b.*?(?=^  -|\Z)", text, re.M | re.S)
    assert found, f"{option} is not in the help:\n{text}"
    return " ".join(found.group(0).split())


@pytest.mark.parametrize("command", COMMANDS)
def test_help_shows_every_default(capsys, command):
    """Each option that has a value when not given shows it in --help, as the parser uses it."""
    parser = cli_args.build_parser("boxmarch", dict.fromkeys(COMMANDS), "boxmarch")
    defaults = vars(parser.parse_args([command, *REQUIRED.get(command, [])]))
    assert cli.run([command, "--help"]) == 0
    text = capsys.readouterr().out
    shown = 0
    for dest, value in defaults.items():
        given = "--" + dest.replace("_", "-") in REQUIRED.get(command, [])
        if value is None or value is False or given or dest in ("command", "run"):
            continue
        assert f"(default: {value})" in option_help(text, "--" + dest.replace("_", "-")), (dest, value)
        shown += 1
    # Control: the options with defaults were found (--origin ... --random-seed, --steps, --tolerance ...).
    assert shown >= {"bake": 7, "dedup": 1, "merge": 1, "pack-uv": 2, "export": 1, "pipeline": 12, "demo": 4}[command]


def test_a_checkout_without_the_native_build_says_how_to_build(tmp_path):
    """``PYTHONPATH=addon python3 -m boxmarch`` before anything was built: one line naming the
    build script, exit code 3, for --version and for a command alike."""
    addon = tmp_path / "addon"
    shutil.copytree(Path(cli.__file__).parent, addon / "boxmarch", ignore=shutil.ignore_patterns("*.so", "__pycache__"))
    env = dict(os.environ, PYTHONPATH=str(addon))
    for argv in (["--version"], ["bake", "world.blend"]):
        r = subprocess.run([sys.executable, "-m", "boxmarch", *argv], cwd=tmp_path, env=env, capture_output=True,
                           text=True, timeout=120)
        err = r.stderr.strip().splitlines()
        assert r.returncode == cli.EXIT_MISSING_MODULE and len(err) == 1, (r.returncode, r.stderr)
        assert err[0].startswith("boxmarch: error: boxmarch's native module") and "scripts/dev_build.sh" in err[0], err


@pytest.mark.parametrize("argv", [["bake"], ["dedup"], ["merge"], ["pack-uv"], ["export", "--to", "x.glb"],
                                  ["pipeline", "--to", "x.glb"]])
def test_a_command_without_a_blend_file_is_refused(blender, capsys, tmp_path, monkeypatch, argv):
    """No FILE.blend and none open (bpy's own startup scene, or the Blender program started without
    a file): exit 2 with one line, and the scene in memory is left as it was, never baked."""
    ob = random_boxes_object(blender)
    monkeypatch.chdir(tmp_path)
    assert blender.data.filepath == ""
    assert cli.run(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"boxmarch: error: {argv[0]}: no .blend file to work on: give FILE.blend"), err
    assert "BoxOffset" not in ob.data.attributes and list(tmp_path.iterdir()) == []

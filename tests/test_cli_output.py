"""What the command line prints in a terminal: tables that fit TABLE_WIDTH columns, --version, and
a missing bpy module named as what to install (its own exit code) rather than an internal error."""
import sys

import pytest

from boxmarch import bl_info, cli


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
    what = " ".join(cells[2] for cells in columns[1:] if cells[2])
    assert f"layout NORMAL_COLOR: {long}" in what and "wrote /a/rather/long/path" in what
    assert "".join(cells[3] for cells in columns[1:]) == "x" * 150
    assert [cells[0] for cells in columns if cells[0]] == ["step", "export GODOT3", "total"]
    # A table that fits is left as it is.
    narrow = cli.format_table(["step", "time"], [["bake", "0.1 s"]])
    assert narrow.splitlines() == ["| step | time  |", "|------|-------|", "| bake | 0.1 s |"]


def test_version_prints_the_add_on_version(capsys):
    assert cli.run(["--version"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"boxmarch {'.'.join(map(str, bl_info['version']))}"), out


@pytest.mark.parametrize("argv", [["bake", "missing.blend"], ["demo", "--count", "100"]])
def test_missing_bpy_says_what_to_install(monkeypatch, capsys, tmp_path, argv):
    monkeypatch.setitem(sys.modules, "bpy", None)  # `import bpy` raises ModuleNotFoundError, as without bpy
    monkeypatch.chdir(tmp_path)
    assert cli.run(argv) == cli.EXIT_NO_BPY == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no bpy module" in err[0] and "pip install bpy==5.0" in err[0], err
    assert list(tmp_path.iterdir()) == []

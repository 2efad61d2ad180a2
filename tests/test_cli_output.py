"""What the command line prints in a terminal: tables that fit TABLE_WIDTH columns, --version, and
a missing bpy module named as what to install (its own exit code) rather than an internal error."""
import sys

import pytest

from boxmarch import bl_info, cli


def test_table_fits_the_width_and_keeps_every_word():
    long = "demo_godot3.glb + demo_godot3.boxmarch.json + demo_godot3.boxes.tres + demo_godot3.glb.import"
    rows = [["export GODOT3", "2.783 s", f"layout NORMAL_COLOR: {long}", "x" * 150],
            ["total", "16.612 s", "wrote /a/rather/long/path/to/demo_out/demo.blend", ""]]
    table = cli._table(["step", "time", "what", "accuracy"], rows)
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
    narrow = cli._table(["step", "time"], [["bake", "0.1 s"]])
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
        table = cli._table(["step", "time", "what", "accuracy"], rows, width=width)
        lines = [line for line in table.splitlines()[2:]]
        assert max(map(len, lines)) <= width, table
        for column in range(4):
            read = " ".join(line.strip("|").split(" | ")[column].strip() for line in lines).replace("/ ", "/")
            assert read.split() == " ".join(row[column] for row in rows).split(), (column, table)
    narrow = cli._table(["step", "what"], [["total", "wrote /home/someone/a-rather-long-folder-name/x.blend"]], width=40)
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
    assert cli.run(argv) == cli.EXIT_NO_BPY == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no bpy module" in err[0] and "pip install bpy==5.0" in err[0], err
    assert list(tmp_path.iterdir()) == []

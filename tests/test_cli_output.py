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
    what = " ".join(cells[2] for cells in columns[1:] if cells[2])
    assert f"layout NORMAL_COLOR: {long}" in what and "wrote /a/rather/long/path" in what
    assert "".join(cells[3] for cells in columns[1:]) == "x" * 150
    assert " ".join(cells[0] for cells in columns if cells[0]) == "step export GODOT3 total"
    # A table that fits is left as it is.
    narrow = cli._table(["step", "time"], [["bake", "0.1 s"]])
    assert narrow.splitlines() == ["| step | time  |", "|------|-------|", "| bake | 0.1 s |"]


def test_table_breaks_cells_between_words_only():
    """The demo's rows (issue 37: 'e | ngines/unreal/...'): every word whole on one line of its
    column; a path wider than any column it could get breaks only after a '/'."""
    from boxmarch.formats import presets

    rows = [[f"export {name}", "0.812 s", f"layout {preset.layouts[0]}: demo_{name.lower()}.fbx + "
             f"demo_{name.lower()}.boxmarch.json + demo_{name.lower()}.boxes.bin",
             f"default import loses 4.9e-04 of half-extent: {preset.import_fix}"]
            for name, preset in presets.PRESETS.items() if preset.import_fix]
    assert any("engines/unreal/" in row[3] for row in rows)  # the word that was cut
    table = cli._table(["step", "time", "what", "accuracy"], rows)
    lines = table.splitlines()
    assert max(map(len, lines)) <= cli.TABLE_WIDTH, table
    cells = [[cell.strip() for cell in line.strip("|").split(" | ")] for line in lines if not line.startswith("|-")]
    for row in rows:
        for column, cell in enumerate(row):
            for word in cell.split():
                assert any(word in line_cells[column].split() for line_cells in cells), (word, table)
    path = "/home/someone/projects/a-rather-long-folder-name/boxmarch/demo_out/demo.blend"
    narrow = cli._table(["step", "what"], [["total", f"wrote {path}"]], width=40).splitlines()
    pieces = [line.strip("|").split(" | ")[1].strip() for line in narrow[2:]]
    assert "".join(pieces) == f"wrote {path}" and all(p.endswith("/") for p in pieces[:-1]), narrow


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

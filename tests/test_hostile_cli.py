"""Hostile inputs to the command line, round 2 (issue 21; docs/CHECKS.md lists them): a refused
output is never written, not even with the error report; every file an export writes is an
output; runs writing the same files at once; names of up to 255 bytes; SIGINT; arguments after
``--``; bad input that must end in one line and exit 2, never an internal error."""
import json
import os
import shutil
import signal
import subprocess
import sys

import pytest

from boxmarch.formats import files
from tests.gltf_reader import read_glb
from tests.helpers.blender_program import SCRIPTS, module_environment, run_module
from tests.conftest import digest


def last_line(proc):
    return proc.stderr.strip().splitlines()[-1]


@pytest.mark.slow
def test_a_refused_json_is_not_written_even_with_the_error(baked_blend, tmp_path):
    before = digest(baked_blend)
    r = run_module(["bake", str(baked_blend), "--json", str(baked_blend)], tmp_path)
    assert r.returncode == 2 and "--json" in last_line(r) and "is the input file" in last_line(r), r.stderr
    assert digest(baked_blend) == before
    for option, name in (("--to", "X.glb"), ("--out", "X.blend")):
        earlier = tmp_path / name
        earlier.write_bytes(b"an earlier result")
        r = run_module(["export", str(baked_blend), "--to", "other.glb", option, name, "--json", name], tmp_path)
        assert r.returncode == 2 and "name the same file" in last_line(r), r.stderr
        assert earlier.read_bytes() == b"an earlier result"
    assert sorted(os.listdir(tmp_path)) == ["X.blend", "X.glb", "world.blend"]  # no other.glb, no sidecar


@pytest.mark.slow
def test_every_file_an_export_writes_is_an_output(baked_blend, tmp_path):
    table = tmp_path / "g.boxes.tres"
    table.write_text("an earlier box table")
    r = run_module(["export", str(baked_blend), "--preset", "GODOT3", "--to", "g.glb", "--json", "g.boxes.tres"],
                   tmp_path)
    assert r.returncode == 2 and "the export beside --to" in last_line(r), r.stderr
    assert table.read_text() == "an earlier box table" and not (tmp_path / "g.glb").exists()
    r = run_module(["export", str(baked_blend), "--preset", "GODOT3", "--to", "g.glb", "--json", "r.json"], tmp_path)
    assert r.returncode == 0, r.stderr
    files_written = json.loads((tmp_path / "r.json").read_text())["steps"][0]["files"]
    assert files_written == [str(tmp_path / name) for name in ("g.glb", "g.boxmarch.json", "g.boxes.tres",
                                                                "g.glb.import")]
    assert table.read_text().startswith("[gd_resource")
    # The demo's own files are its outputs too: a --json among them is refused before it starts.
    r = run_module(["demo", "--count", "100", "--out", "d", "--json", "d/demo_godot3.boxes.tres"], tmp_path)
    assert r.returncode == 2 and "name the same file" in last_line(r), r.stderr
    assert not (tmp_path / "d").exists()


def test_two_writers_of_one_file_at_once_both_succeed_and_the_last_wins(tmp_path):
    path = tmp_path / "same.json"

    def first(temp):
        with open(temp, "w") as f:
            f.write("first")
        files.write_atomically(path, lambda other: open(other, "w").close())  # a second run, meanwhile

    files.write_atomically(path, first)
    assert path.read_text() == "first" and os.listdir(tmp_path) == ["same.json"]


@pytest.mark.slow
def test_a_second_run_writing_the_same_outputs_meanwhile_both_succeed(baked_blend, tmp_path):
    """The second run starts and ends while the first holds its export under the temporary name."""
    r = subprocess.run([sys.executable, str(SCRIPTS / "second_run_during_export.py"), "export", str(baked_blend),
                        "--preset", "GODOT3", "--to", "same.glb", "--out", "same.blend", "--json", "same.json"],
                       cwd=tmp_path, env=module_environment(tmp_path), capture_output=True, text=True, timeout=240)
    assert r.returncode == 0 and "second run: exit 0" in r.stderr, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["same.blend", "same.boxes.tres", "same.boxmarch.json", "same.glb",
                                            "same.glb.import", "same.json", "world.blend"]
    assert json.loads((tmp_path / "same.json").read_text())["ok"]
    assert [m["name"] for m in read_glb(tmp_path / "same.glb")] == ["Baked"]


def test_output_checks_follow_symbolic_links(tmp_path):
    """check_outputs judges the file a link names (files.written_path): two links to one file
    are one output, a link to the input is the input, a link into a missing folder names that
    folder, links that loop are refused; a plain link to a new file passes."""
    from boxmarch import cli_args

    (tmp_path / "world.blend").write_bytes(b"input")
    (tmp_path / "target.glb").write_bytes(b"earlier")
    for name, target in (("a.glb", "target.glb"), ("b.json", "target.glb"), ("in.glb", "world.blend"),
                         ("lost.glb", "missing/x.glb"), ("loop1.glb", "loop2.glb"), ("loop2.glb", "loop1.glb"),
                         ("new.glb", "made.glb")):
        os.symlink(target, tmp_path / name)
    inputs = [str(tmp_path / "world.blend")]
    for outputs, words in (([("--to", "a.glb"), ("--json", "b.json")], "name the same file"),
                           ([("--to", "in.glb")], "is the input file"),
                           ([("--to", "lost.glb")], f"folder '{tmp_path / 'missing'}' does not exist"),
                           ([("--to", "loop1.glb")], "loop")):
        with pytest.raises(cli_args.InputError, match=words):
            cli_args.check_outputs([(o, str(tmp_path / p)) for o, p in outputs], inputs)
    cli_args.check_outputs([("--to", str(tmp_path / "new.glb")), ("--json", str(tmp_path / "a.glb"))], inputs)


def test_partial_names_stay_within_name_max():
    for name, ending in (("a" * 251 + ".glb", ".boxmarch-partial.glb"),
                         ("é" * 124 + ".blend", ".boxmarch-partial.blend"),
                         ("r." + "x" * 252, ".boxmarch-partial")):  # an extension too long to keep is dropped
        assert len(name.encode()) <= files.NAME_MAX
        temp = os.path.basename(files.partial_path(os.path.join("/folder", name)))
        assert len(temp.encode()) <= files.NAME_MAX - files.WRITER_SUFFIX_ROOM and temp.endswith(ending), temp
        assert temp.startswith("." + os.path.splitext(name)[0][:10])  # hidden, named after the file
    assert files.partial_path("/f/x.glb") != files.partial_path("/f/x.glb")


# The longest --to whose sidecar NAME.boxmarch.json still fits in 255 bytes: 255 - len(".boxmarch.json").
LONGEST_STEM = 255 - len(".boxmarch.json")


@pytest.mark.parametrize("stem, out", [("a" * LONGEST_STEM, "b" * 249 + ".blend"), ("é" * (LONGEST_STEM // 2), None)],
                         ids=["241-byte-stem-255-byte-blend", "240-byte-utf8-stem"])
@pytest.mark.slow
def test_output_names_up_to_255_bytes_are_written(baked_blend, tmp_path, stem, out):
    to = stem + ".glb"
    r = run_module(["export", str(baked_blend), "--to", to] + (["--out", out] if out else []), tmp_path)
    assert r.returncode == 0, r.stderr
    beside = [stem + ".boxmarch.json", stem + ".boxes.bin"]  # the sidecar and the box table
    assert sorted(os.listdir(tmp_path)) == sorted(["world.blend", to, *beside] + ([out] if out else []))


@pytest.mark.slow
def test_a_to_whose_sidecar_name_passes_255_bytes_is_refused(baked_blend, tmp_path):
    to = "a" * (LONGEST_STEM + 1) + ".glb"  # 246 bytes itself, its sidecar 256
    r = run_module(["export", str(baked_blend), "--to", to], tmp_path)
    assert r.returncode == 2 and ".boxmarch.json' is 256 bytes, longer than the 255" in last_line(r), r.stderr
    assert os.listdir(tmp_path) == ["world.blend"]


@pytest.mark.slow
def test_a_name_longer_than_255_bytes_is_refused(baked_blend, tmp_path):
    r = run_module(["export", str(baked_blend), "--to", "a" * 253 + ".glb"], tmp_path)
    assert r.returncode == 2 and "257 bytes, longer than the 255" in last_line(r), r.stderr
    assert os.listdir(tmp_path) == ["world.blend"]


# Signals that end a process unless handled, which someone else sends (docs/CLI.md).
TERMINATING = ["SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2", "SIGALRM", "SIGVTALRM", "SIGPROF",
               "SIGXCPU", "SIGPWR", "SIGIO"]


def test_the_command_line_handles_every_terminating_signal():
    from boxmarch.formats.files import TERMINATING_SIGNALS

    assert sorted(signal.Signals(s).name for s in TERMINATING_SIGNALS) == sorted(TERMINATING)


@pytest.mark.parametrize("name", TERMINATING)
@pytest.mark.slow
def test_a_terminating_signal_during_the_fbx_export_leaves_no_file(baked_blend, tmp_path, name):
    """Each signal that would end the process (Ctrl-C, a closed terminal, a service manager's
    stop, ...) exits 128 + its number, with no temporary file left and the report written."""
    r = subprocess.run([sys.executable, str(SCRIPTS / "interrupted_fbx_export.py"), name, "export", str(baked_blend),
                        "--preset", "UNITY", "--to", "w.fbx", "--json", "r.json"], cwd=tmp_path,
                       env=module_environment(tmp_path), capture_output=True, text=True, timeout=240)
    code = 128 + getattr(signal, name)
    assert r.returncode == code, r.stderr
    assert last_line(r).startswith(f"boxmarch: interrupted: stopped by {name},"), r.stderr
    assert sorted(os.listdir(tmp_path)) == ["r.json", "world.blend"]
    assert json.loads((tmp_path / "r.json").read_text())["exit_code"] == code


@pytest.mark.slow
def test_module_form_keeps_the_arguments_before_a_double_dash(baked_blend, tmp_path):
    shutil.copy(baked_blend, tmp_path / "-w.blend")
    r = run_module(["bake", "--out", "o.blend", "--", "-w.blend"], tmp_path)
    assert r.returncode == 0 and (tmp_path / "o.blend").exists(), r.stderr


@pytest.mark.slow
def test_pack_uv_refuses_the_baked_quaternion_map(baked_blend, tmp_path):
    before = digest(baked_blend)
    r = run_module(["pack-uv", str(baked_blend), "--uv-map", "BoxQuatXY", "--out", "p.blend"], tmp_path)
    assert r.returncode == 2 and "'BoxQuatXY' holds the baked box frame" in last_line(r), r.stderr
    assert "pack the texture UV map ('UVMap')" in last_line(r)
    assert digest(baked_blend) == before and os.listdir(tmp_path) == ["world.blend"]


@pytest.mark.parametrize("args, reason", [
    (["demo", "--out", "notes.txt"], "is a file: the demo writes its files into a folder"),
    (["demo", "--count", str(2**40)], "--count must be in 100..1,000,000"),
    (["demo", "--seed", "-1"], "--seed must be 0 or more"),
])
@pytest.mark.slow
def test_demo_arguments_that_were_internal_errors(tmp_path, args, reason):
    (tmp_path / "notes.txt").write_text("a file")
    r = run_module(args, tmp_path)
    assert r.returncode == 2 and last_line(r).startswith("boxmarch: error:") and reason in last_line(r), r.stderr
    assert os.listdir(tmp_path) == ["notes.txt"]


def test_an_operator_traceback_becomes_one_line(monkeypatch, capsys):
    from boxmarch import cli

    def broken(_args):  # what bpy.ops raises when an exporter fails in Python
        raise RuntimeError('Error: Python: Traceback (most recent call last):\n  File "export.py", line 85\n'
                           "OSError: [Errno 28] No space left on device\nLocation: bpy/ops.py:109\n")

    monkeypatch.setattr(cli, "cmd_bake", broken)
    assert cli.run(["bake"]) == 1
    assert capsys.readouterr().err.strip().splitlines() == [
        "boxmarch: internal error: RuntimeError: OSError: [Errno 28] No space left on device"]

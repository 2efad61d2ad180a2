"""The add-on inside Debian's Blender program (3.4): a background bake, and undo in a real window
under Xvfb (the bpy module has no window, so undo needs the program)."""
import json
import shutil
import subprocess

import pytest

from tests.helpers.blender_program import SCRIPTS, blender_env, run_blender

pytestmark = [pytest.mark.slow, pytest.mark.blender_program]  # Blender 3.4 program subprocesses


@pytest.mark.parametrize("encoding, tolerance", [("FLOAT_COLOR", 1e-5), ("BYTE_COLOR", 0.05)])
def test_background_bake_in_blender_program(package_parent, tmp_path, encoding, tolerance):
    out = tmp_path / "result.json"
    run_blender(["--background", "--factory-startup", "--python-exit-code", "1",
                 "--python", str(SCRIPTS / "bake_check.py"), "--", str(package_parent), str(out), encoding],
                tmp_path)
    result = json.loads(out.read_text())
    assert result["result"] == ["FINISHED"]
    assert result["uv_layers"] == ["UVMap", "BoxQuatXY", "BoxQuatZW"]
    assert result["max_relative_error"] <= tolerance
    if encoding == "BYTE_COLOR":
        assert result["alpha_max"] <= 1.0


def test_undo_in_a_window(package_parent, tmp_path):
    if shutil.which("xvfb-run") is None:
        pytest.fail("xvfb-run is missing: run scripts/setup.sh")
    out = tmp_path / "undo.json"
    run_blender_cmd = ["-a", "-s", "-screen 0 1024x768x24", shutil.which("blender"), "--factory-startup",
                       "--python", str(SCRIPTS / "undo_check.py"), "--", str(package_parent), str(out)]
    proc = subprocess.run(["xvfb-run", *run_blender_cmd], env=blender_env(tmp_path), capture_output=True,
                          text=True, timeout=240)
    assert out.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads(out.read_text())
    assert result["error"] is None, result["error"]
    assert result["object_mode"] == {"after_bake": True, "after_undo": False}
    assert result["edit_mode"] == {"after_bake": True, "after_undo": False}

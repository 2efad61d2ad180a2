"""The add-on as users install it: scripts/build_extension.sh makes a legacy zip (Blender 3.x) and
a 4.2+ extension zip (manifest + platform wheel, built and validated by Blender's own extension
tool); each is installed into a fresh, temporary user configuration, enabled, and bakes."""
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from helpers.blender_program import SCRIPTS, blender_env

pytestmark = pytest.mark.slow  # builds the zips and installs them into both Blenders

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run(["bash", str(REPO / "scripts" / "build_extension.sh"), str(out)], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "Success parsing TOML" in proc.stdout  # the extension tool validated the manifest
    return {"legacy": out / "boxmarch-0.1.0-legacy-linux-x64.zip", "extension": out / "boxmarch-0.1.0.zip"}


def test_zips_hold_what_each_blender_needs(packages):
    legacy = zipfile.ZipFile(packages["legacy"]).namelist()
    assert "boxmarch/__init__.py" in legacy and "boxmarch/_core.cpython-311-x86_64-linux-gnu.so" in legacy
    assert "boxmarch/blender_manifest.toml" not in legacy
    assert "boxmarch/shaders/glsl/preview.frag.glsl" in legacy
    extension = zipfile.ZipFile(packages["extension"]).namelist()
    assert "blender_manifest.toml" in extension and "__init__.py" in extension
    assert "shaders/glsl/preview.frag.glsl" in extension
    assert not [n for n in extension if n.endswith(".so")]  # the native module travels in the wheel
    wheel = next(n for n in extension if n.endswith(".whl"))
    with zipfile.ZipFile(packages["extension"]).open(wheel) as f:
        inner = zipfile.ZipFile(f).namelist()
    assert "boxmarch_native/_core.cpython-311-x86_64-linux-gnu.so" in inner


def check(result, root):
    assert result["error"] is None, result["error"]
    assert result["enabled"] and result["bake"] == ["FINISHED"]
    assert result["module_file"].startswith(str(root)) and result["core_file"].startswith(str(root))
    assert result["max_relative_error"] < 1e-5
    assert result["shader_dir"].startswith(str(root)) and result["preview_covered"] > 0.01


def test_legacy_zip_installs_into_clean_blender_34_and_bakes(packages, tmp_path):
    env = blender_env(tmp_path / "home")
    (tmp_path / "home").mkdir()
    env["BLENDER_USER_CONFIG"] = str(tmp_path / "config")
    env["BLENDER_USER_SCRIPTS"] = str(tmp_path / "scripts")
    out = tmp_path / "result.json"
    proc = subprocess.run([shutil.which("blender"), "--background", "--factory-startup", "--python",
                           str(SCRIPTS / "install_check.py"), "--", str(packages["legacy"]), str(out)],
                          env=env, capture_output=True, text=True, timeout=300)
    assert out.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads(out.read_text())
    assert result["error"] is None, result["error"]
    assert result["version"][:2] == [3, 4]
    check(result, tmp_path / "scripts")


def test_extension_installs_into_clean_blender_5_and_bakes(packages, tmp_path):
    """The bpy module is Blender 5.0: its extensions operator installs the zip and its wheel."""
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # only the installed copy may load
    env.update(HOME=str(home), TMPDIR=str(home), XDG_CACHE_HOME=str(home), XDG_CONFIG_HOME=str(home),
               BLENDER_USER_RESOURCES=str(tmp_path / "resources"))
    out = tmp_path / "result.json"
    proc = subprocess.run([sys.executable, str(SCRIPTS / "install_check.py"), "--", str(packages["extension"]), str(out)],
                          env=env, capture_output=True, text=True, timeout=300)
    assert out.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads(out.read_text())
    assert result["error"] is None, result["error"]
    assert result["version"][:2] >= [4, 2]
    check(result, tmp_path / "resources")

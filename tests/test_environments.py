"""The checkout's Python environments (scripts/environments.sh): each README command keeps its
Python packages in its own virtual environment (.venv-demo, .venv-test) and builds boxmarch into it
from its own build folder; the other scripts run with whichever of the two exists, so they work
after either command; bpy's other releases and zig's caches stay inside the checkout. And the
getting-started picture, run after the demo alone (no Godot), makes its three.js half."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"


def sourced(expression, **env):
    """What bash prints for ``expression`` after sourcing scripts/environments.sh, with ``env`` set
    (a value of None unsets the variable)."""
    environ = dict(os.environ)
    for name in ("PYTHON", "BOXMARCH_DEMO_VENV", "BOXMARCH_TEST_VENV", "BOXMARCH_CACHE"):
        environ.pop(name, None)
    environ.update({k: v for k, v in env.items() if v is not None})
    return subprocess.run(["bash", "-c", f"source scripts/environments.sh; {expression}"], cwd=ROOT, env=environ,
                          capture_output=True, text=True, check=True, timeout=30).stdout.strip()


def code_lines(script):
    """The lines of ``script`` (a scripts/ file) that are not comments."""
    return [line for line in (SCRIPTS / script).read_text().splitlines() if not line.lstrip().startswith("#")]


def fake_venv(folder):
    (folder / "bin").mkdir(parents=True)
    (folder / "bin" / "python").write_text("#!/bin/sh\n")
    (folder / "bin" / "python").chmod(0o755)
    return folder


def test_scripts_run_with_the_python_of_either_environment(tmp_path):
    demo, test = tmp_path / ".venv-demo", tmp_path / ".venv-test"
    venvs = {"BOXMARCH_DEMO_VENV": str(demo), "BOXMARCH_TEST_VENV": str(test)}
    assert sourced("checkout_python", **venvs) == "python3"  # neither command ran yet
    fake_venv(demo)
    assert sourced("checkout_python", **venvs) == f"{demo}/bin/python"  # after the demo alone
    fake_venv(test)
    assert sourced("checkout_python", **venvs) == f"{test}/bin/python"  # the tests' has every tool
    assert sourced("checkout_python", PYTHON="/opt/other/python", **venvs) == "/opt/other/python"
    # The defaults: the two folders of the checkout .gitignore keeps out of git.
    assert sourced('echo "$DEMO_VENV $TEST_VENV"') == f"{ROOT}/.venv-demo {ROOT}/.venv-test"
    assert {"/.venv-demo/", "/.venv-test/"} <= set((ROOT / ".gitignore").read_text().split())


def test_every_script_that_runs_python_takes_the_checkout_python():
    """No script falls back to the machine's python3 by itself (which has neither environment's
    packages): the two set-ups make their environment from it, test.sh runs the test environment's,
    every other script asks checkout_python."""
    makers = {"demo.sh", "setup.sh"}  # PYTHON there is the Python the environment is made from
    for script in sorted(p.name for p in SCRIPTS.glob("*.sh") if p.name != "environments.sh"):
        code = "\n".join(code_lines(script))
        if '"$PYTHON"' not in code:
            continue
        if script in makers:
            assert re.search(r'"\$PYTHON" -m venv "\$(VENV|TEST_VENV)"', code), script
        elif script == "test.sh":
            assert 'PYTHON="$TEST_VENV/bin/python"' in code
        else:
            assert 'PYTHON="$(checkout_python)"' in code and "python3}" not in code, script


def test_each_environment_builds_boxmarch_in_its_own_folder():
    """demo.sh and setup.sh build into different folders, so one never reconfigures the other's
    CMake cache for its own Python (the issue: 4 minutes of rebuilding)."""
    folders = sourced('venv_build_dir "$DEMO_VENV"; venv_build_dir "$TEST_VENV"').split()
    assert folders == ["build/venv-demo", "build/venv-test"]
    for script, venv in (("demo.sh", "$VENV"), ("setup.sh", "$TEST_VENV")):
        builds = [line for line in code_lines(script)
                  if re.search(r"pip (install|wheel) ", line) and re.search(r" \.( &)?$", line.rstrip())]
        assert builds and all(f'-C build-dir="$(venv_build_dir "{venv}")"' in line for line in builds), (script, builds)


def test_the_test_command_installs_into_its_own_environment():
    code = code_lines("setup.sh")
    pip_calls = [line for line in code if "pip install" in line and "echo" not in line]
    assert pip_calls and all(line.strip().startswith('"$TEST_PYTHON" -m pip install') for line in pip_calls), pip_calls
    assert '[ -x "$TEST_VENV/bin/python" ] || "$PYTHON" -m venv "$TEST_VENV"' in code  # no --system-site-packages
    assert 'PYTHON="$TEST_PYTHON" bash scripts/install_bpy.sh 4.2 >/dev/null' in code
    # boxmarch compiles beside those installs, and the set-up waits for it (its failure is the set-up's)
    assert code.index('wait "$build"') > code.index('build=$!')


def test_downloads_stay_in_the_checkout(tmp_path):
    """bpy's other releases and zig's caches go to .cache in the checkout (BOXMARCH_CACHE moves it),
    never to /var/cache or the home folder."""
    assert sourced('echo "$BOXMARCH_CACHE"') == f"{ROOT}/.cache"
    assert sourced('echo "$BOXMARCH_CACHE"', BOXMARCH_CACHE=str(tmp_path)) == str(tmp_path)
    assert "/.cache/" in (ROOT / ".gitignore").read_text().split()
    # A complete folder is reused: install_bpy.sh prints it and installs nothing.
    (tmp_path / "bpy-4.2").mkdir()
    (tmp_path / "bpy-4.2" / ".complete").touch()
    printed = subprocess.run(["bash", str(SCRIPTS / "install_bpy.sh"), "4.2"], capture_output=True, text=True,
                             env=dict(os.environ, BOXMARCH_CACHE=str(tmp_path)), check=True, timeout=30).stdout
    assert printed.strip() == str(tmp_path / "bpy-4.2")
    for script in SCRIPTS.glob("*.sh"):
        code = "\n".join(code_lines(script.name))
        assert "/var/" not in code and "$HOME" not in code and "~/" not in code, script.name
    assert 'ZIG_GLOBAL_CACHE_DIR="$BOXMARCH_CACHE/zig"' in "\n".join(code_lines("cross_compile.sh"))


@pytest.mark.slow
def test_getting_started_picture_without_godot_makes_the_threejs_half(blender, tmp_path, monkeypatch, capsys):
    """After the demo alone (Chromium and three.js r111, no Godot 3), the one-liner writes the
    three.js picture, says the Godot 3 one is left out, and exits 0."""
    from scripts import getting_started_picture
    from tests.engines import godot3

    def no_godot(*_args, **_kwargs):
        raise AssertionError("Godot 3 was run")

    monkeypatch.setattr(godot3, "available", lambda: "godot3 is not installed (apt-get install godot3)")
    monkeypatch.setattr(godot3, "import_gltf", no_godot)
    monkeypatch.setattr(godot3, "render", no_godot)
    drawn = {}
    write_png = getting_started_picture.write_png
    monkeypatch.setattr(getting_started_picture, "write_png",
                        lambda path, rgba: (drawn.setdefault(os.path.basename(path), rgba), write_png(path, rgba)))
    monkeypatch.setattr(sys, "argv", ["getting_started_picture", "--out-folder", str(tmp_path)])
    assert getting_started_picture.main() == 0
    out = capsys.readouterr().out
    assert "godot3_chain.png not made: godot3 is not installed" in out, out
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(drawn) == ["getting_started_chain.png"]
    alpha = drawn["getting_started_chain.png"][..., 3]
    assert alpha.shape == (getting_started_picture.HEIGHT, getting_started_picture.WIDTH)
    assert (alpha > 0).mean() > 0.01, (alpha > 0).mean()  # the links are drawn

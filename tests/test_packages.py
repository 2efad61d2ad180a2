"""The two commands install by job: scripts/demo.sh only the demo's packages (scripts/packages.sh),
its Python packages into a virtual environment; scripts/setup.sh (the test command's) those and
the test tools. The lists are read as bash reads them."""
import importlib.metadata
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"


def _name(spec):
    """A pip requirement's project name, normalized (PEP 503), or an apt package's name."""
    return re.sub(r"[-_.]+", "-", re.split(r"[<>=!~ \[;]", spec, maxsplit=1)[0]).lower()


def demo_packages():
    out = subprocess.run(["bash", "-c", 'source scripts/packages.sh; printf "apt %s\\n" "${DEMO_APT_PACKAGES[@]}"; '
                          'printf "pip %s\\n" "${DEMO_PIP_PACKAGES[@]}"'], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    return _kinds(out)


def setup_packages():
    out = subprocess.run(["bash", str(SCRIPTS / "setup.sh"), "--list"], cwd=ROOT, capture_output=True, text=True,
                         check=True, timeout=30).stdout
    return _kinds(out)


def _kinds(listing):
    kinds = {"apt": set(), "pip": set()}
    for line in listing.splitlines():
        kind, spec = line.split(" ", 1)
        kinds[kind].add(_name(spec))
    return kinds


def test_demo_installs_a_strict_subset_of_the_test_command():
    demo, setup = demo_packages(), setup_packages()
    for kind in ("apt", "pip"):
        assert demo[kind] and demo[kind] <= setup[kind], (kind, demo[kind] - setup[kind])
    # The demo leaves out the test toolchain (the 1.7 GB: Godot, mono, bpy 4.2, zig, ...).
    for tool in ("blender", "godot3", "mono-mcs", "clang-14", "xvfb"):
        assert tool in setup["apt"] and tool not in demo["apt"], tool
    for tool in ("pytest", "ziglang", "nicegui", "ufbx", "ruff"):
        assert tool in setup["pip"] and tool not in demo["pip"], tool
    # What the demo's two programs import beyond the standard library and boxmarch: bpy (which
    # brings NumPy) and, to build the native module, its build backend.
    assert {"bpy", "scikit-build-core", "pybind11"} <= demo["pip"]


def test_demo_installs_python_packages_into_its_own_environment():
    script = (SCRIPTS / "demo.sh").read_text()
    code = "\n".join(line for line in script.splitlines() if not line.lstrip().startswith("#"))
    assert "setup.sh" not in code and "install_bpy" not in code  # not the test command's set-up
    assert "source scripts/packages.sh" in code and '-m venv "$VENV"' in code
    pip_calls = [line for line in code.splitlines() if "pip install" in line and "echo" not in line]
    assert pip_calls and all(line.strip().startswith('"$DEMO_PYTHON" -m pip install') for line in pip_calls), pip_calls
    assert re.search(r'"\$DEMO_PYTHON" -m boxmarch demo', code) and "scripts.threejs_picture" in code
    assert "/.venv-demo/" in (ROOT / ".gitignore").read_text().split()


def installed_closure(names) -> list:
    """The installed distributions ``names`` need, with their requirements (extras left out),
    transitively."""
    found, todo = {}, list(names)
    while todo:
        dist = importlib.metadata.distribution(todo.pop())
        name = _name(dist.metadata["Name"])
        if name in found:
            continue
        found[name] = dist
        for text in dist.requires or ():
            requirement = Requirement(text)
            if requirement.marker is None or requirement.marker.evaluate({"extra": ""}):
                todo.append(requirement.name)
    return list(found.values())


@pytest.mark.slow
def test_the_demo_runs_with_only_the_demo_packages(package_parent, tmp_path):
    """python3 -m boxmarch demo and scripts/threejs_picture.py, run with no site-packages but the
    demo's Python packages (DEMO_PIP_PACKAGES and boxmarch's own dependencies, with everything they
    require, as pip puts them into .venv-demo): nothing else the test command installs is needed."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    wanted = demo_packages()["pip"] | {_name(spec) for spec in pyproject["project"]["dependencies"]}
    site = tmp_path / "site"
    site.mkdir()
    for dist in installed_closure(wanted):
        for top in {file.parts[0] for file in dist.files or () if file.parts[0] not in ("..", "__pycache__")}:
            if not (site / top).exists():
                (site / top).symlink_to(dist.locate_file(top))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(map(str, (site, package_parent, ROOT))),
               HOME=str(tmp_path), TMPDIR=str(tmp_path), XDG_CACHE_HOME=str(tmp_path / "cache"))
    env.pop("BOXMARCH_BPY_PATH", None)
    # Control: -S leaves this Python's site-packages out, so a test-only package is not found.
    control = subprocess.run([sys.executable, "-S", "-c", "import jsonschema"], env=env, capture_output=True)
    assert control.returncode != 0
    for command in (["-m", "boxmarch", "demo", "--count", "100", "--preview", "CPU", "--out", "out"],
                    ["-m", "scripts.threejs_picture", "--out", "out"]):
        proc = subprocess.run([sys.executable, "-S", *command], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=600)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert (tmp_path / "out" / "demo.glb").stat().st_size > 0 and (tmp_path / "out" / "demo_threejs.png").is_file()

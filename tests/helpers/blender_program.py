"""Running the add-on outside this process: Debian's Blender program (3.4) with a clean
environment, and ``python -m boxmarch`` (or a check script) with this Python and its bpy module.

``BOXMARCH_BPY_PATH`` names a folder holding another release's bpy module (``pip install --target``,
see scripts/install_bpy.sh): conftest puts it first on this process's sys.path and ``python_env``
puts it first on a child Python's, so every test that runs the bpy module runs that release."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import boxmarch

SCRIPTS = Path(__file__).resolve().parent.parent / "blender_scripts"
BPY_PATH = os.environ.get("BOXMARCH_BPY_PATH", "")


def blender_env(tmp_path):
    env = dict(os.environ)
    for var in ("HOME", "TMPDIR", "XDG_CACHE_HOME", "XDG_CONFIG_HOME"):
        env[var] = str(tmp_path)
    env.pop("PYTHONPATH", None)
    # Debian's Blender finds its Python home through the first python3 on PATH: it must be the
    # system one, not the (pyenv or venv) Python running these tests.
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    return env


def run_blender(args, tmp_path, timeout=240):
    blender = shutil.which("blender")
    assert blender, "Debian's blender is missing: run scripts/setup.sh"
    proc = subprocess.run([blender, *args], env=blender_env(tmp_path), capture_output=True, text=True,
                          timeout=timeout)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def python_env(env, *folders):
    """``env`` for a child Python that imports bpy: PYTHONPATH holds BPY_PATH (when set), then folders."""
    path = [str(p) for p in (BPY_PATH, *folders) if p]
    if path:
        env["PYTHONPATH"] = os.pathsep.join(path)
    else:
        env.pop("PYTHONPATH", None)
    return env


def module_environment(cwd):
    """The environment of a ``python -m boxmarch`` run in ``cwd``: BPY_PATH and this boxmarch on
    the path, Blender's caches in a folder beside ``cwd`` (outside the checked folder)."""
    env = python_env(dict(os.environ), Path(boxmarch.__file__).parent.parent)
    home = Path(cwd).parent / f"{Path(cwd).name}-home"
    home.mkdir(exist_ok=True)
    for var in ("HOME", "TMPDIR", "XDG_CACHE_HOME"):
        env[var] = str(home)
    return env


def run_module(args, cwd, timeout=240):
    return subprocess.run([sys.executable, "-m", "boxmarch", *args], cwd=cwd, env=module_environment(cwd),
                          capture_output=True, text=True, timeout=timeout)

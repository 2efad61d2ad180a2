"""The house rules CI enforces (CONTRIBUTING.md): ruff's lint over the Python trees, the layer
contracts of docs/ARCHITECTURE.md (import-linter, configured in pyproject.toml) over the add-on,
and the cpp/ style of .clang-format over the files already written in it. scripts/setup.sh
installs the three tools; a missing tool fails here rather than skipping the check."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PYTHON_TREES = ["addon", "tests", "bench", "scripts", "shaders"]
# Every cpp/ and bindings/ source keeps the .clang-format layout, except shader_library.h, which
# shaders/generate.py writes in the generator's layout.
FORMATTED_CPP = sorted(str(path.relative_to(ROOT)) for tree in ("cpp", "bindings") for pattern in ("*.cpp", "*.h")
                       for path in (ROOT / tree).rglob(pattern) if path.name != "shader_library.h")


def run(command):
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_ruff_finds_nothing():
    proc = run([sys.executable, "-m", "ruff", "check", "--no-cache", *PYTHON_TREES])
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]


def test_ruff_catches_an_unused_import(tmp_path):
    """Negative control: the configuration in pyproject.toml does report a planted finding."""
    planted = tmp_path / "planted.py"
    planted.write_text("import os\n")
    proc = run([sys.executable, "-m", "ruff", "check", "--no-cache", "--config", str(ROOT / "pyproject.toml"),
                str(planted)])
    assert proc.returncode == 1 and "F401" in proc.stdout, proc.stdout + proc.stderr


def lint_imports(package_parent):
    """import-linter over the boxmarch package found in ``package_parent``."""
    command = [sys.executable, "-c", "from importlinter.cli import lint_imports_command; lint_imports_command()",
               "--no-cache", str(ROOT / "pyproject.toml")]
    return subprocess.run(command, cwd=package_parent, env=dict(os.environ, PYTHONPATH=str(package_parent)),
                          capture_output=True, text=True, timeout=300)


def test_imports_keep_the_layer_contracts():
    proc = lint_imports(ROOT / "addon")
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]
    assert "2 kept, 0 broken" in proc.stdout, proc.stdout[-2000:]


@pytest.mark.parametrize("module, planted, contract", [
    ("core.py", "from . import mesh_io", "Layers"),      # the core reaching up to the Blender door
    ("formats/layouts.py", "import bpy", "never import Blender"),  # a format-facing module importing Blender
    ("formats/fbx_container.py", "from io_scene_fbx import parse_fbx", "never import Blender"),  # Blender's add-on
])
def test_lint_imports_catches_a_planted_import(tmp_path, module, planted, contract):
    """Negative control: a copy of the package with one forbidden import breaks its contract."""
    shutil.copytree(ROOT / "addon" / "boxmarch", tmp_path / "boxmarch", ignore=shutil.ignore_patterns("*.so"))
    with open(tmp_path / "boxmarch" / module, "a") as f:
        f.write(f"\n{planted}  # planted\n")
    proc = lint_imports(tmp_path)
    broken = [line for line in proc.stdout.splitlines() if " BROKEN" in line]
    assert proc.returncode == 1 and any(contract in line for line in broken), proc.stdout[-3000:] + proc.stderr[-2000:]


def clang_format():
    tool = shutil.which("clang-format-14") or shutil.which("clang-format")
    if tool is None:
        pytest.fail("clang-format is missing: run scripts/setup.sh")
    return tool


def test_formatted_cpp_files_keep_the_style():
    proc = run([clang_format(), "--dry-run", "-Werror", *FORMATTED_CPP])
    assert proc.returncode == 0, proc.stderr[-5000:]


def test_clang_format_catches_a_style_change(tmp_path):
    """Negative control: a file from the list with one indent changed fails the same check."""
    source = (ROOT / FORMATTED_CPP[0]).read_text()
    drifted = tmp_path / "drifted.cpp"
    drifted.write_text(source.replace("\n    ", "\n  ", 1))
    shutil.copy(ROOT / ".clang-format", tmp_path / ".clang-format")
    proc = run([clang_format(), "--dry-run", "-Werror", str(drifted)])
    assert proc.returncode != 0 and "drifted.cpp" in proc.stderr, proc.stderr

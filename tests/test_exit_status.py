"""pytest under bpy 4.2 (which segfaults at interpreter exit once the add-on registered) ends with
its own status: tests/conftest.py's pytest_unconfigure leaves with os._exit of it, so a passing
run exits 0 and a failing one 1, never 139."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import boxmarch

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def bpy_42():
    proc = subprocess.run(["bash", str(REPO / "scripts" / "install_bpy.sh"), "4.2"],
                          env=dict(os.environ, PYTHON=sys.executable), capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip()


@pytest.mark.slow
@pytest.mark.parametrize("fail, status, summary", [("0", 0, "1 passed"), ("1", 1, "1 failed")])
def test_pytest_status_survives_the_exit_crash(bpy_42, tmp_path, fail, status, summary):
    env = dict(os.environ, BOXMARCH_BPY_PATH=bpy_42, BOXMARCH_PROBE_FAIL=fail, TMPDIR=str(tmp_path),
               PYTHONPATH=str(Path(boxmarch.__file__).parent.parent))
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           str(REPO / "tests" / "helpers" / "exit_probe.py")],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == status, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert summary in proc.stdout.splitlines()[-1]

"""The GitHub Actions workflows (.github/workflows) pass actionlint, which checks their syntax, the
runner labels, expressions, the inputs of known actions and, through shellcheck, their run: scripts.
They are not run here (they need GitHub's runners); docs/PLATFORMS.md says what they do."""
import subprocess
from pathlib import Path

import pytest

from tests.helpers.tools import python_program

WORKFLOWS = Path(__file__).resolve().parent.parent / ".github" / "workflows"


def actionlint(*paths):
    program = python_program("actionlint")
    if program is None:
        pytest.fail("actionlint is missing: run scripts/setup.sh")
    return subprocess.run([program, "-no-color", *map(str, paths)], capture_output=True, text=True, timeout=120)


def test_workflows_pass_actionlint():
    files = sorted(WORKFLOWS.glob("*.yml"))
    assert [f.name for f in files] == ["wheels.yml"]
    proc = actionlint(*files)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_actionlint_finds_the_mistakes_it_is_trusted_with(tmp_path):
    """Negative control: an unknown runner label, an undefined matrix key and an unquoted
    variable in a run: script are each reported."""
    broken = tmp_path / "broken.yml"
    broken.write_text((WORKFLOWS / "wheels.yml").read_text()
                      .replace("windows-2022", "windows-1999")
                      .replace("name: wheel-${{ matrix.os }}", "name: wheel-${{ matrix.system }}")
                      .replace('python -m pip install "bpy==4.2.*"', "cd $HOME/x && ls"))
    proc = actionlint(broken)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    for finding in ('label "windows-1999" is unknown', 'property "system" is not defined', "SC2086"):
        assert finding in proc.stdout, proc.stdout

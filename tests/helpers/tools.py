"""The one way a test meets a missing tool: it fails, naming the tool and scripts/setup.sh, which
installs every tool the tests use (engines, compilers, parsers, libraries). A missing tool never
skips a check, on CI (CI=true) or anywhere else: a check that did not run would read as one that
passed. tests/test_house.py fails on any pytest.skip, importorskip or skip marker in tests/."""
import os
import shutil
import sysconfig

import pytest


def need(reason):
    """Returns when ``reason`` is None (the tool is there), else fails the test with it."""
    if reason:
        pytest.fail(f"{reason}: run scripts/setup.sh (a missing tool fails, never skips)", pytrace=False)


def python_program(name):
    """The path of a command a Python package installs (actionlint), looked up first beside this
    Python (its environment's bin folder, .venv-test/bin, whether or not that is on PATH), then on
    PATH; None when neither has it."""
    return shutil.which(name, path=os.pathsep.join([sysconfig.get_path("scripts"), os.environ.get("PATH", "")]))

"""The sanitizer checks, run by the test suite (and so by CI; the native tier's other files:
tests/test_fuzz.py, tests/test_cross_compile.py, which scripts/test.sh runs beside this file):

* the AddressSanitizer + UndefinedBehaviorSanitizer build of the core passes its C++ tests and the
  replay of the kept fuzz corpus (scripts/sanitize.sh cpp);
* the native Python test suite passes against the sanitized module (scripts/sanitize.sh python),
  after the first (the same build folder).

Each runs a script in a subprocess and fails with its output when the script fails: a sanitizer
report or a failed C++ check ends in a nonzero exit. The scripts need libasan and cmake, which
scripts/setup.sh installs.
"""
import os
import pathlib
import subprocess
import sys

import pytest

# Their own tier (-m native), minutes each: also slow, so the everyday tier skips them.
pytestmark = [pytest.mark.slow, pytest.mark.native]

ROOT = pathlib.Path(__file__).resolve().parents[1]


def run_script(*args, timeout):
    env = dict(os.environ, PYTHON=sys.executable)
    done = subprocess.run(["bash", *args], cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    output = done.stdout[-20000:] + "\n" + done.stderr[-20000:]
    assert done.returncode == 0, output
    return output


def test_sanitizer_build_passes_the_cpp_tests_and_the_fuzz_corpus():
    output = run_script("scripts/sanitize.sh", "cpp", timeout=1800)
    assert "100% tests passed" in output
    assert "0 failure(s)" in output


def test_native_python_suite_passes_under_asan_and_ubsan():
    output = run_script("scripts/sanitize.sh", "python", timeout=1800)
    assert " passed" in output and " failed" not in output

"""The libFuzzer target (fuzz/fuzz_core.cpp, clang's ASan + UBSan + libFuzzer build in build/fuzz)
runs clean for its CI budget, starting from the kept corpus (scripts/fuzz.sh, BOXMARCH_FUZZ_SECONDS,
default 60): a crash or a sanitizer report ends the script in a nonzero exit and fails the test
with its output. Its own file, so scripts/test.sh runs it beside the sanitizer checks
(tests/test_native_checks.py), whose build it shares nothing with. Needs clang-14 and
libclang-rt-14-dev, which scripts/setup.sh installs.
"""
import os

import pytest

from tests.test_native_checks import run_script

# The native tier (-m native): minutes, so also slow, and the everyday tier skips it.
pytestmark = [pytest.mark.slow, pytest.mark.native]


def test_fuzz_target_runs_clean_for_its_ci_budget():
    seconds = os.environ.get("BOXMARCH_FUZZ_SECONDS", "60")
    output = run_script("scripts/fuzz.sh", seconds, timeout=int(seconds) + 900)
    assert "Done" in output and "stat::number_of_executed_units" in output

"""The native check of the fuzzer, run by the test suite (and so by CI): the libFuzzer target runs
clean for its CI budget, starting from the kept corpus (scripts/fuzz.sh, BOXMARCH_FUZZ_SECONDS,
default 60). A file of its own, so the native tier's workers (--dist loadfile) run it beside the
sanitizer checks (tests/test_native_checks.py), which share one build folder.
"""
import os

import pytest

from tests.test_native_checks import run_script

pytestmark = [pytest.mark.slow, pytest.mark.native]


def test_fuzz_target_runs_clean_for_its_ci_budget():
    seconds = os.environ.get("BOXMARCH_FUZZ_SECONDS", "60")
    output = run_script("scripts/fuzz.sh", seconds, timeout=int(seconds) + 900)
    assert "Done" in output and "stat::number_of_executed_units" in output

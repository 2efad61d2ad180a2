"""The one way a test meets a missing tool: it fails, naming the tool and scripts/setup.sh, which
installs every tool the tests use (engines, compilers, parsers, libraries). A missing tool never
skips a check, on CI (CI=true) or anywhere else: a check that did not run would read as one that
passed. tests/test_house.py fails on any pytest.skip, importorskip or skip marker in tests/."""
import pytest


def need(reason):
    """Returns when ``reason`` is None (the tool is there), else fails the test with it."""
    if reason:
        pytest.fail(f"{reason}: run scripts/setup.sh (a missing tool fails, never skips)", pytrace=False)

"""Run only by tests/test_exit_status.py (its name keeps it out of the normal collection): a test
that registers the add-on under the bpy module and fails when BOXMARCH_PROBE_FAIL=1."""
import os


def test_probe(blender):
    assert hasattr(blender.types, "BOXMARCH_OT_bake")
    assert os.environ.get("BOXMARCH_PROBE_FAIL") != "1", "failing on purpose"

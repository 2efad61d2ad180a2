"""Shared by the preview's render checks (tests/test_preview.py, tests/test_preview_pose.py): a check
script run in both Blenders, and the comparison with the CPU reference raymarch."""
import subprocess
import sys

import numpy as np

import pytest

from tests.helpers.blender_program import blender_env, python_env, run_blender

# The two ways of running the add-on, marked for scripts/blender_matrix.py's selections.
BLENDERS = [pytest.param("blender-3.4-program", marks=pytest.mark.blender_program),
            pytest.param("bpy-module", marks=pytest.mark.bpy)]


def run_check_script(blender, script, package_parent, out, tmp):
    """Runs ``script -- PACKAGE_PARENT OUT`` in ``blender`` (one of BLENDERS); returns OUT's arrays."""
    if blender == "blender-3.4-program":
        run_blender(["--background", "--factory-startup", "--python-exit-code", "1", "--python", str(script), "--",
                     str(package_parent), str(out)], tmp, timeout=600)
    else:
        proc = subprocess.run([sys.executable, str(script), "--", str(package_parent), str(out)],
                              env=python_env(blender_env(tmp)), capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return dict(np.load(out))


def quaternions_of(rotations):
    """(n, 4) x, y, z, w of proper rotation matrices (n, 3, 3), Shepperd's way with signs from
    the antisymmetric part: written here independently of the code under test."""
    m = np.asarray(rotations)
    w = np.sqrt(np.maximum(0, 1 + m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2])) / 2
    x = np.sqrt(np.maximum(0, 1 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2])) / 2
    y = np.sqrt(np.maximum(0, 1 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2])) / 2
    z = np.sqrt(np.maximum(0, 1 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2])) / 2
    x = np.copysign(x, m[:, 2, 1] - m[:, 1, 2])
    y = np.copysign(y, m[:, 0, 2] - m[:, 2, 0])
    z = np.copysign(z, m[:, 1, 0] - m[:, 0, 1])
    return np.stack([x, y, z, w], 1)


# core.render_boxes options that march to the exact surface: the reference for the presets, which
# the preview and the engines solve in closed form (shaders/glsl/raymarch.glsl bm_preset_hit); the
# CPU reference's own defaults (epsilon 1e-3, 64 steps, forward differences) are the preview's
# march, a user's map()'s.
EXACT_MARCH = {"epsilon": 1e-6, "max_steps": 512, "normal": "CENTRAL"}


def agreement(depth, ref):
    """(coverage agreement, 99.9th percentile of |depth difference| where both hit)."""
    both = (depth < 1.0) & (ref.depth < 1.0)
    return ((depth < 1.0) == (ref.depth < 1.0)).mean(), np.percentile(np.abs(depth - ref.depth)[both], 99.9)

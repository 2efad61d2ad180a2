"""bench/bench_gpu_frame.py compiles what bench/gpu_frame_data.py assembles: every stage (the
preview with and without the depth declaration, its diagnostic variants, the naive full-screen
raymarch) passes glslangValidator, and the declared stage differs from the undeclared one by the
gl_FragDepth layout alone."""
import subprocess

import pytest

from tests.helpers.glsl import validator

from bench import gpu_frame_data  # noqa: E402


@pytest.mark.parametrize("sdf", ["SPHERE", "LINK"])
def test_every_stage_compiles(tmp_path, sdf):
    stages = gpu_frame_data.stage_sources(sdf)
    for name, source in stages.items():
        path = tmp_path / f"{name}.{'vert' if name.endswith('vertex') else 'frag'}"
        path.write_text(source)
        proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
        assert proc.returncode == 0, f"{name}:\n{proc.stdout}{proc.stderr}"
    declared = stages["fragment_depth_greater"].splitlines()
    undeclared = stages["fragment_undeclared"].splitlines()
    assert [line for line in declared if line not in undeclared] == ["layout(depth_greater) out float gl_FragDepth;"]
    assert "gl_FragDepth" not in stages["fragment_face_depth"]
    assert "discard" not in stages["fragment_depth_greater_no_discard"]


def test_a_broken_stage_fails(tmp_path):
    """Negative control: the validator rejects the preview stage without Blender's declarations."""
    path = tmp_path / "bare.frag"
    path.write_text("#version 430 core\n" + gpu_frame_data.shader_sources.fragment_source("SPHERE"))
    proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
    assert proc.returncode != 0

"""GLSL checks with glslangValidator: a stage is compiled with the declarations Blender's
GPUShaderCreateInfo adds in front of it (uniform block, vertex inputs, stage interface, outputs)."""
import shutil
import subprocess

import pytest

from boxmarch.formats import shader_sources


def validator():
    path = shutil.which("glslangValidator")
    if path is None:
        pytest.fail("glslangValidator is missing: apt-get install glslang-tools (scripts/setup.sh)")
    return path


# What Blender generates from the preview's create-info before our source (GL backend).
blender_declarations = shader_sources.gl_declarations


def compile_glsl(tmp_path, name, stage, source, layout="CLASSIC"):
    path = tmp_path / f"{name}.{stage}"
    path.write_text(blender_declarations(stage, layout) + source)
    return subprocess.run([validator(), str(path)], capture_output=True, text=True)

"""GLSL checks with glslangValidator: a stage is compiled with the declarations Blender's
GPUShaderCreateInfo adds in front of it (uniform block, vertex inputs, stage interface, outputs)."""
import shutil
import subprocess

import pytest

from boxmarch.preview import sources

GLSL_TYPES = {"FLOAT": "float", "INT": "int", "VEC2": "vec2", "VEC3": "vec3", "VEC4": "vec4", "MAT4": "mat4"}


def validator():
    path = shutil.which("glslangValidator")
    if path is None:
        pytest.fail("glslangValidator is missing: apt-get install glslang-tools (scripts/setup.sh)")
    return path


def blender_declarations(stage, layout="CLASSIC"):
    """What Blender generates from the preview's create-info before our source (GL backend)."""
    lines = ["#version 330 core", sources.UNIFORM_STRUCT,
             f"layout(std140) uniform _{sources.UNIFORM_NAME} {{ {sources.UNIFORM_TYPE} {sources.UNIFORM_NAME}; }};"]
    if stage == "vert":
        lines += [f"layout(location = {i}) in {GLSL_TYPES[t]} {name};" for i, (t, name) in enumerate(sources.VERTEX_INPUTS[layout])]
    direction = "out" if stage == "vert" else "in"
    lines += [f"{'flat ' if interp == 'flat' else ''}{direction} {GLSL_TYPES[t]} {name};"
              for interp, t, name in sources.STAGE_INTERFACE]
    if stage == "frag":
        lines += [f"layout(location = {slot}) out {GLSL_TYPES[t]} {name};" for slot, t, name in sources.FRAGMENT_OUTPUTS]
    return "\n".join(lines) + "\n"


def compile_glsl(tmp_path, name, stage, source, layout="CLASSIC"):
    path = tmp_path / f"{name}.{stage}"
    path.write_text(blender_declarations(stage, layout) + source)
    return subprocess.run([validator(), str(path)], capture_output=True, text=True)

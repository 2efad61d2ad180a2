"""Shader checks with glslangValidator: a preview GLSL stage is compiled with the declarations
Blender's GPUShaderCreateInfo adds in front of it (uniform block, vertex inputs, stage interface,
outputs); an engine's HLSL is compiled as a fragment stage by glslang's HLSL front end."""
import shutil
import subprocess
import tempfile

from boxmarch.formats import shader_sources
from tests.helpers.tools import need


def validator():
    path = shutil.which("glslangValidator")
    need(None if path else "glslangValidator is missing (apt-get install glslang-tools)")
    return path


# What Blender generates from the preview's create-info before our source (GL backend).
blender_declarations = shader_sources.gl_declarations


def compile_glsl(tmp_path, name, stage, source, layout="CLASSIC"):
    path = tmp_path / f"{name}.{stage}"
    path.write_text(blender_declarations(stage, layout) + source)
    return subprocess.run([validator(), str(path)], capture_output=True, text=True)


def compile_hlsl_fragment(tmp_path, name, source):
    """glslang's HLSL front end on ``source`` as a fragment stage whose entry is ``main``, written
    to ``tmp_path / name`` (an engine's code wrapped as the engine wraps it)."""
    path = tmp_path / name
    path.write_text(source)
    return subprocess.run([validator(), "-D", "-V", "-e", "main", "-S", "frag", str(path), "-o", str(tmp_path / "out.spv")],
                          capture_output=True, text=True, timeout=60)


def preprocessed(fragment: str) -> str:
    """The fragment source as its compile sees it: its #ifdef branches taken (glslangValidator -E)."""
    with tempfile.NamedTemporaryFile("w", suffix=".frag") as source:
        source.write(fragment)
        source.flush()
        proc = subprocess.run([validator(), "-E", source.name], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return proc.stdout

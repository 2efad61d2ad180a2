"""The engine shaders and the CPU reference's SDF library come from one source (shaders/glsl): the
generated files must be what shaders/generate.py writes now (and a drifted body must be caught),
and the three.js file must load as a script and as an ES module."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from tests.helpers.tools import need

SHADERS = Path(__file__).resolve().parent.parent / "shaders"
EXPORTS = ["boxmarchClosedOutward", "boxmarchDecodeVectors", "boxmarchOccluderShape", "boxmarchSidecarUrl", "boxmarchTexcoordName",
           "boxmarchVisibilitySupported", "checkBoxmarchOptions", "checkBoxmarchSidecar", "createBoxmarchMaterial",
           "createBoxmarchOccluderMaterial", "loadBoxmarch", "parseBoxmarchSidecar", "prepareBoxmarchGeometry",
           "sortBoxmarchFrontToBack", "useBoxmarchBackFaceCulling", "useBoxmarchMaterial", "useBoxmarchOccluders",
           "useBoxmarchVisibility"]


def test_generated_engine_shaders_are_up_to_date():
    proc = subprocess.run([sys.executable, str(SHADERS / "generate.py"), "--check"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_generated_files_carry_the_shared_decode_verbatim():
    decode = (SHADERS / "glsl" / "decode.glsl").read_text()
    godot = (SHADERS / "godot3" / "boxmarch.shader").read_text()
    block_end = decode.index("\n//\n") + 4  # the conventions block, which the template carries once
    assert decode.startswith("// Conventions of every boxmarch shader")
    assert decode[block_end:] in godot and godot.count(decode[:block_end]) == 1
    hlsl = (SHADERS / "hlsl" / "boxmarch_decode.hlsl").read_text()
    assert decode.replace("vec3", "float3").replace("vec2", "float2").replace("vec4", "float4") in hlsl


def copy_of_the_generated_tree(tmp_path):
    """shaders/ (generator, sources, outputs), the generated C++, the engine packages' copies
    (engines/) and the march's ranges the generator reads (march_ranges.py) at their relative paths."""
    shutil.copytree(SHADERS, tmp_path / "shaders")
    shutil.copytree(SHADERS.parent / "engines", tmp_path / "engines")
    (tmp_path / "addon" / "boxmarch" / "formats").mkdir(parents=True)
    shutil.copy(SHADERS.parent / "addon" / "boxmarch" / "formats" / "march_ranges.py",
                tmp_path / "addon" / "boxmarch" / "formats")
    (tmp_path / "cpp" / "src").mkdir(parents=True)
    shutil.copy(SHADERS.parent / "cpp" / "src" / "shader_library.h", tmp_path / "cpp" / "src")
    return tmp_path


def run_generator(root, *args):
    return subprocess.run([sys.executable, str(root / "shaders" / "generate.py"), *args], capture_output=True, text=True)


@pytest.mark.parametrize("relative, body, drifted", [
    ("shaders/hlsl/boxmarch_sdf.hlsl", "return length(p) - r;", "return length(p) - 0.9 * r;"),
    ("shaders/hlsl/boxmarch_march.hlsl", "float advance = relaxation * d;", "float advance = d;"),
    ("cpp/src/shader_library.h", "return glm::length(p) - r;", "return glm::length(p) - 0.9f * r;"),
    ("shaders/godot3/boxmarch.shader", "return length(p) - r;", "return length(p) - 0.9 * r;"),
    ("engines/unity/com.boxmarch.boxmarch/Runtime/Shaders/boxmarch_sdf.hlsl", "return length(p) - r;",
     "return length(p) - 0.9 * r;"),
    ("engines/unity/com.boxmarch.boxmarch/Runtime/Shaders/BoxmarchExample.shader", "Cull Off", "Cull Back"),
    ("engines/godot3/addons/boxmarch/boxmarch.shader", "return length(p) - r;", "return length(p) - 0.9 * r;")])
def test_a_drifted_generated_body_is_caught(tmp_path, relative, body, drifted):
    root = copy_of_the_generated_tree(tmp_path)
    assert run_generator(root, "--check").returncode == 0
    path = root / relative
    text = path.read_text()
    assert text.count(body) == 1
    path.write_text(text.replace(body, drifted))
    proc = run_generator(root, "--check")
    assert proc.returncode == 1
    assert relative in proc.stderr


@pytest.mark.parametrize("builtin", ["mod(p.x, 1.0)", "fract(p.x)", "atan(p.y, p.x)"])
def test_generator_refuses_a_builtin_it_cannot_translate(tmp_path, builtin):
    """mod() floors in GLSL where HLSL's fmod() truncates: copied as it is, it would change meaning."""
    root = copy_of_the_generated_tree(tmp_path)
    sdf = root / "shaders" / "glsl" / "sdf.glsl"
    sdf.write_text(sdf.read_text() + f"float sd_drifted(vec3 p) {{ return {builtin}; }}\n")
    proc = run_generator(root)
    assert proc.returncode != 0
    assert f"no HLSL translation for: {builtin.split('(')[0]}" in proc.stderr


@pytest.mark.parametrize("name, loader", [
    ("boxmarch.js", "const m = require(process.argv[1]);"),
    ("boxmarch.module.js", "const m = await import('file://' + process.argv[1]);")])
def test_threejs_material_loads_as_script_and_module(name, loader):
    node = shutil.which("node") or shutil.which("nodejs")
    need(None if node else "node is not installed (apt-get install nodejs)")
    script = f"(async () => {{ {loader} console.log(Object.keys(m).sort().join(',')); }})();"
    proc = subprocess.run([node, "-e", script, str(SHADERS / "threejs" / name)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ",".join(EXPORTS)

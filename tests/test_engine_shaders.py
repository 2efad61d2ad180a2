"""The engine shaders come from one source (shaders/glsl): the generated files must be what
shaders/generate.py writes now, and the three.js file must load as a script and as an ES module."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

SHADERS = Path(__file__).resolve().parent.parent / "shaders"
EXPORTS = ["boxmarchTexcoordName", "createBoxmarchMaterial", "prepareBoxmarchGeometry", "useBoxmarchMaterial"]


def test_generated_engine_shaders_are_up_to_date():
    proc = subprocess.run([sys.executable, str(SHADERS / "generate.py"), "--check"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_generated_files_carry_the_shared_decode_verbatim():
    decode = (SHADERS / "glsl" / "decode.glsl").read_text()
    godot = (SHADERS / "godot3" / "boxmarch.shader").read_text()
    assert decode in godot
    hlsl = (SHADERS / "hlsl" / "boxmarch_decode.hlsl").read_text()
    assert decode.replace("vec3", "float3").replace("vec2", "float2").replace("vec4", "float4") in hlsl


@pytest.mark.parametrize("name, loader", [
    ("boxmarch.js", "const m = require(process.argv[1]);"),
    ("boxmarch.module.js", "const m = await import('file://' + process.argv[1]);")])
def test_threejs_material_loads_as_script_and_module(name, loader):
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None:
        pytest.skip("node is not installed")
    script = f"(async () => {{ {loader} console.log(Object.keys(m).sort().join(',')); }})();"
    proc = subprocess.run([node, "-e", script, str(SHADERS / "threejs" / name)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ",".join(EXPORTS)

"""The shipped HLSL run on a real GPU pipeline: Unity cannot run here, so its material's HLSL is
compiled as Unity's compilers would take it (glslangValidator, HLSL front end, to SPIR-V),
translated to GLSL ES 3.0 by SPIRV-Cross (Debian's spirv-cross), and drawn with WebGL 2 in
headless Chromium (SwiftShader) from vertex arrays the caller gives: what Unity's importer holds
(tests/engine_scene.py models it). The translation changes syntax, not arithmetic, so the
pixels show what the HLSL computes.

``render`` binds every vertex input by the name SPIRV-Cross gives it (``v_<field>`` of the
vertex program's input struct) and fills the ``$Global`` constant buffer member by member at
the offsets WebGL reports, so no std140 packing is written by hand here.
"""
import base64
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from . import threejs

_JOB = """function () {
  var d = __DATA__;
  var canvas = document.createElement('canvas');
  canvas.width = d.width; canvas.height = d.height;
  var gl = canvas.getContext('webgl2', {antialias: false, preserveDrawingBuffer: true});
  if (!gl) throw new Error('no WebGL 2');
  function stage(type, source) {
    var s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  var p = gl.createProgram();
  gl.attachShader(p, stage(gl.VERTEX_SHADER, d.vertex));
  gl.attachShader(p, stage(gl.FRAGMENT_SHADER, d.fragment));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  gl.useProgram(p);
  var bytes = function (b64) { return Uint8Array.from(atob(b64), function (c) { return c.charCodeAt(0); }); };
  gl.bindVertexArray(gl.createVertexArray());
  Object.keys(d.attributes).forEach(function (name) {
    var a = d.attributes[name], at = gl.getAttribLocation(p, name);
    if (at < 0) return;  // an input the program does not use
    gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(bytes(a.data).buffer), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(at);
    gl.vertexAttribPointer(at, a.size, gl.FLOAT, false, 0, 0);
  });
  var block = gl.getUniformBlockIndex(p, d.block);
  if (block === gl.INVALID_INDEX) throw new Error('no uniform block ' + d.block);
  var size = gl.getActiveUniformBlockParameter(p, block, gl.UNIFORM_BLOCK_DATA_SIZE);
  var data = new ArrayBuffer(size), f32 = new Float32Array(data), i32 = new Int32Array(data);
  var members = gl.getActiveUniformBlockParameter(p, block, gl.UNIFORM_BLOCK_ACTIVE_UNIFORM_INDICES);
  var offsets = gl.getActiveUniforms(p, members, gl.UNIFORM_OFFSET);
  Array.prototype.forEach.call(members, function (index, k) {
    var info = gl.getActiveUniform(p, index), name = info.name.split('.').pop();
    if (!(name in d.uniforms)) throw new Error('no value for ' + info.name);
    var values = [].concat(d.uniforms[name]), at = offsets[k] / 4;
    var ints = info.type === gl.INT;
    values.forEach(function (v, j) { if (ints) i32[at + j] = v; else f32[at + j] = v; });
  });
  gl.bindBuffer(gl.UNIFORM_BUFFER, gl.createBuffer());
  gl.bufferData(gl.UNIFORM_BUFFER, data, gl.STATIC_DRAW);
  gl.uniformBlockBinding(p, block, 0);
  gl.bindBufferBase(gl.UNIFORM_BUFFER, 0, gl.getParameter(gl.UNIFORM_BUFFER_BINDING));
  gl.viewport(0, 0, d.width, d.height);
  gl.clearColor(0, 0, 0, 0);
  gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  gl.drawArrays(gl.TRIANGLES, 0, d.count);
  var px = new Uint8Array(d.width * d.height * 4);
  gl.readPixels(0, 0, d.width, d.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
  var err = gl.getError();
  if (err) throw new Error('WebGL error ' + err);
  return {pixels: __b64(px)};
}"""


def available():
    """None when glslangValidator, spirv-cross and Chromium with three.js are installed, else why not."""
    for tool, package in (("glslangValidator", "glslang-tools"), ("spirv-cross", "spirv-cross")):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (apt-get install {package})"
    return threejs.available()


def to_glsl_es(hlsl_path, entry, stage, defines=(), include_dirs=()):
    """GLSL ES 3.00 of the HLSL entry point ``entry`` (``stage``: vert or frag) of ``hlsl_path``."""
    with tempfile.TemporaryDirectory(prefix="boxmarch-hlsl-") as tmp:
        spv = str(Path(tmp) / f"{entry}.spv")
        proc = subprocess.run(["glslangValidator", "-D", "-V", *[f"-D{d}" for d in defines],
                               *[f"-I{d}" for d in include_dirs], "-e", entry, "-S", stage, str(hlsl_path), "-o", spv],
                              capture_output=True, text=True)
        if proc.returncode:
            raise RuntimeError(f"glslangValidator failed:\n{proc.stdout}{proc.stderr}")
        # WebGL links the stages' varyings by name: both sides get one name per location.
        direction = "out" if stage == "vert" else "in"
        renames = [a for n in range(16) for a in ("--rename-interface-variable", direction, str(n), f"bm_varying{n}")]
        proc = subprocess.run(["spirv-cross", spv, "--es", "--version", "300", "--rename-entry-point", entry, "main",
                               stage, *renames], capture_output=True, text=True)
        if proc.returncode:
            raise RuntimeError(f"spirv-cross failed:\n{proc.stderr}")
        return proc.stdout


def render(vertex_glsl, fragment_glsl, attributes, uniforms, count, width, height, block="_Global"):
    """(H, W, 4) uint8 RGBA, row 0 at the top, of ``count`` vertices drawn as triangles (no depth
    test) on transparent black. ``attributes``: vertex input name -> float (count, k) array;
    ``uniforms``: member name of the constant buffer ``block`` -> number or list (a float4x4
    column by column, as HLSL's default column_major packing holds it); a member without a value
    fails."""
    data = {"vertex": vertex_glsl, "fragment": fragment_glsl, "width": width, "height": height, "count": int(count),
            "block": block, "uniforms": uniforms,
            "attributes": {name: {"size": int(np.shape(a)[1]),
                                  "data": base64.b64encode(np.ascontiguousarray(a, np.float32).tobytes()).decode()}
                           for name, a in attributes.items()}}
    out = threejs.run_page(b"", _JOB.replace("__DATA__", json.dumps(data)))
    pixels = np.frombuffer(base64.b64decode(out["pixels"]), np.uint8).reshape(height, width, 4)
    return pixels[::-1].copy()

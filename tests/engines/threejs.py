"""three.js r111 (Debian's libjs-three) in headless Chromium on SwiftShader's WebGL 1.

Each call writes one self-contained page (three.min.js, the classic GLTFLoader.js and the .glb as
base64 inlined, so no file-access flags are needed), runs ``chromium --headless --dump-dom`` on it
with a fresh profile, and reads the results the page wrote into ``<pre id="out">``: JSON whose
arrays travel as base64 Float64Array/Uint8Array bytes, so every float arrives bit-exactly. Errors
thrown by the page (and ``console.error``, where three.js reports shader compile errors) become a
``RuntimeError`` with the message.
"""
import base64
import html
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile

import numpy as np

from . import Shot, ndc_to_pixels

THREE_JS = "/usr/share/javascript/three/build/three.min.js"
GLTF_LOADER_JS = "/usr/share/javascript/three/examples/js/loaders/GLTFLoader.js"
CHROMIUM = "chromium"
TIMEOUT_S = 60

_PAGE = """<!DOCTYPE html><html><body><pre id="out"></pre>
<script>
var __errors = [];
window.onerror = function (msg, src, line, col, err) { __errors.push(String(err && err.stack || msg)); };
var __consoleError = console.error;
console.error = function () { __errors.push(Array.prototype.join.call(arguments, ' ')); __consoleError.apply(console, arguments); };
function __b64(bytes) {
  var s = '';
  for (var i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  return btoa(s);
}
function __f64(values) { return __b64(new Uint8Array(new Float64Array(values).buffer)); }
function __finish(result) {
  document.querySelectorAll('script').forEach(function (s) { s.remove(); });
  document.getElementById('out').textContent = JSON.stringify(__errors.length ? {errors: __errors} : result);
}
</script>
<script>__THREE__</script>
<script>__LOADER__</script>
<script>__MATERIAL__</script>
<script>
(function () {
  var bytes = Uint8Array.from(atob('__GLB__'), function (c) { return c.charCodeAt(0); });
  var job = __JOB__;
  if (!bytes.length) {  // a page without a model: the job gets null
    try { __finish(job(null)); } catch (e) { __errors.push(String(e && e.stack || e)); __finish(null); }
    return;
  }
  try {
    new THREE.GLTFLoader().parse(bytes.buffer, '', function (gltf) {
      try { __finish(job(gltf)); } catch (e) { __errors.push(String(e && e.stack || e)); __finish(null); }
    }, function (e) { __errors.push('GLTFLoader: ' + String(e && e.message || e)); __finish(null); });
  } catch (e) { __errors.push(String(e && e.stack || e)); __finish(null); }
})();
</script></body></html>"""

_LOAD_JOB = """function (gltf) {
  gltf.scene.updateMatrixWorld(true);
  var meshes = [];
  gltf.scene.traverse(function (o) {
    if (!(o.isMesh || o.isSkinnedMesh)) return;
    var g = o.geometry, attributes = {};
    Object.keys(g.attributes).forEach(function (name) {
      var a = g.attributes[name], n = a.itemSize, v = new Float64Array(a.count * n);
      var get = [a.getX, a.getY, a.getZ, a.getW];
      for (var i = 0; i < a.count; i++) for (var k = 0; k < n; k++) v[i * n + k] = get[k].call(a, i);
      attributes[name] = {itemSize: n, normalized: !!a.normalized, data: __f64(v)};
    });
    var index = null;
    if (g.index) { var ix = []; for (var i = 0; i < g.index.count; i++) ix.push(g.index.getX(i)); index = __f64(ix); }
    meshes.push({name: o.name, attributes: attributes, index: index, matrixWorld: __f64(o.matrixWorld.elements)});
  });
  return meshes;
}"""

_RENDER_JOB = """function (gltf) {
  var W = __W__, H = __H__, cam = __CAMERA__;
  var canvas = document.createElement('canvas');
  var renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: false, alpha: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(1);
  renderer.setSize(W, H, false);
  renderer.setClearColor(0x000000, 0);
  var near = cam.near || 0.1, far = cam.far || 1000, camera;
  if (cam.ortho !== undefined) {
    var hh = cam.ortho, hw = hh * W / H;
    camera = new THREE.OrthographicCamera(-hw, hw, hh, -hh, near, far);
  } else {
    camera = new THREE.PerspectiveCamera(cam.fov, W / H, near, far);
  }
  camera.position.fromArray(cam.position);
  camera.up.fromArray(cam.up || [0, 1, 0]);
  camera.lookAt(new THREE.Vector3().fromArray(cam.target));
  camera.updateMatrixWorld(true);
  var scene = new THREE.Scene();
  scene.add(gltf.scene);
  (function (THREE, scene, gltf, camera) {
    __SETUP__
  })(THREE, scene, gltf, camera);
  renderer.render(scene, camera);
  var gl = renderer.getContext(), px = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
  return {pixels: __b64(px), view: __f64(camera.matrixWorldInverse.elements),
          projection: __f64(camera.projectionMatrix.elements)};
}"""


def available():
    """None when Chromium and the three.js files are installed, else the reason they are not."""
    if shutil.which(CHROMIUM) is None:
        return "chromium is not installed (apt-get install chromium)"
    for path in (THREE_JS, GLTF_LOADER_JS):
        if not os.path.isfile(path):
            return f"{path} is missing (apt-get install libjs-three)"
    return None


def run_page(glb_bytes, job_js, material_js=""):
    """Runs ``job_js`` (a JS function of the loaded gltf; of null when ``glb_bytes`` is empty) in
    headless Chromium with three.js loaded; returns its JSON result."""
    with open(THREE_JS) as f:
        three = f.read()
    with open(GLTF_LOADER_JS) as f:
        loader = f.read()
    parts = {"__THREE__": three, "__LOADER__": loader, "__MATERIAL__": material_js,
             "__GLB__": base64.b64encode(glb_bytes).decode(), "__JOB__": job_js}
    page = re.sub("|".join(parts), lambda m: parts[m.group(0)], _PAGE)
    with tempfile.TemporaryDirectory(prefix="boxmarch-three-") as tmp:
        path = os.path.join(tmp, "page.html")
        with open(path, "w") as f:
            f.write(page)
        cmd = [CHROMIUM, "--headless", "--no-sandbox", "--use-angle=swiftshader",
               "--enable-unsafe-swiftshader", "--virtual-time-budget=10000",
               f"--user-data-dir={os.path.join(tmp, 'profile')}", "--dump-dom", "file://" + path]
        # own session: on timeout every Chromium process (GPU, renderer) is killed with it
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)
        try:
            stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            raise RuntimeError(f"chromium timed out after {TIMEOUT_S} s:\n{proc.communicate()[1][-4000:]}") from None
    found = re.search(r'<pre id="out">(.*?)</pre>', stdout, re.S)
    if proc.returncode != 0 or not found or not found.group(1):
        raise RuntimeError(f"chromium (exit {proc.returncode}) wrote no result:\n{stderr[-4000:]}")
    result = json.loads(html.unescape(found.group(1)))
    if isinstance(result, dict) and "errors" in result:
        raise RuntimeError("three.js page failed:\n" + "\n".join(result["errors"]))
    return result


def _f64(b64):
    return np.frombuffer(base64.b64decode(b64), dtype=np.float64)


def load_attributes(glb_bytes):
    """What three.js r111's GLTFLoader actually put on the GPU side of every mesh.

    Returns one dict per Mesh/SkinnedMesh in traversal (load) order: ``{"name": str,
    "attributes": {three_name: (count, itemSize) float64 array of the raw BufferAttribute values
    (normalized integer attributes stay raw integers, as r111's getX..getW return them)},
    "normalized": {three_name: bool}, "index": (n,) float64 array or None, "matrixWorld": 4x4}``.
    three_name is r111's: TEXCOORD_0 -> uv, TEXCOORD_1 -> uv2, COLOR_0 -> color, NORMAL ->
    normal, TANGENT -> tangent, POSITION -> position, anything else lower-cased (texcoord_2).
    """
    meshes = []
    for m in run_page(glb_bytes, _LOAD_JOB):
        attrs = m["attributes"]
        meshes.append({
            "name": m["name"],
            "attributes": {k: _f64(a["data"]).reshape(-1, a["itemSize"]) for k, a in attrs.items()},
            "normalized": {k: a["normalized"] for k, a in attrs.items()},
            "index": None if m["index"] is None else _f64(m["index"]),
            "matrixWorld": _f64(m["matrixWorld"]).reshape(4, 4, order="F"),
        })
    return meshes


def render(glb_bytes, material_js, setup_js, width, height, camera):
    """Renders the .glb once with three.js r111 (WebGL 1, SwiftShader) and returns a :class:`Shot`.

    ``material_js``: classic-script JavaScript placed after three.js loads (function definitions,
    e.g. ``createBoxmarchMaterial``). ``setup_js``: a statement list run with ``THREE``, ``scene``,
    ``gltf`` and ``camera`` in scope, typically replacing mesh materials. ``camera``:
    ``{"position", "target", "up" (default +Y), "fov" (vertical degrees)}`` for a
    PerspectiveCamera or ``{"ortho": half_height, ...}`` for an OrthographicCamera with the
    image's aspect; optional ``near`` (0.1) and ``far`` (1000). The clear colour is (0, 0, 0, 0).
    ``Shot.view`` is ``camera.matrixWorldInverse`` and ``Shot.to_pixels`` comes from
    ``camera.projectionMatrix``, both as three.js computed them.
    """
    job = (_RENDER_JOB.replace("__W__", str(int(width))).replace("__H__", str(int(height)))
           .replace("__CAMERA__", json.dumps(camera)).replace("__SETUP__", setup_js))
    out = run_page(glb_bytes, job, material_js)
    pixels = np.frombuffer(base64.b64decode(out["pixels"]), dtype=np.uint8)
    pixels = pixels.reshape(height, width, 4)[::-1].copy()  # readPixels starts at the bottom row
    view = _f64(out["view"]).reshape(4, 4, order="F")
    projection = _f64(out["projection"]).reshape(4, 4, order="F")
    return Shot(pixels, view, ndc_to_pixels(width, height) @ projection @ view)


def pose_bones_js(turns, angle):
    """JavaScript for :func:`render`'s ``setup_js``: turns each bone named in ``turns`` (name ->
    world axis (3,) as the axis points with the skeleton at rest) by ``angle`` radians about its
    own head, on top of its rest rotation, so it carries the bones below it. The axis is moved
    into the bone's local frame with the bones' rest world rotations, read before any turn."""
    return ("gltf.scene.updateMatrixWorld(true);\n"
            f"var bmTurns = {json.dumps({k: [float(x) for x in v] for k, v in turns.items()})}, bmRest = {{}};\n"
            "Object.keys(bmTurns).forEach(function (name) {\n"
            "  var bone = gltf.scene.getObjectByName(name);\n"
            "  if (!bone || !bone.isBone) throw new Error('no bone named ' + name);\n"
            "  bmRest[name] = bone.getWorldQuaternion(new THREE.Quaternion());\n"
            "});\n"
            "Object.keys(bmTurns).forEach(function (name) {\n"
            "  var axis = new THREE.Vector3().fromArray(bmTurns[name]).normalize().applyQuaternion(bmRest[name].clone().inverse());\n"
            f"  gltf.scene.getObjectByName(name).quaternion.multiply(new THREE.Quaternion().setFromAxisAngle(axis, {float(angle)!r}));\n"
            "});\n"
            "gltf.scene.updateMatrixWorld(true);\n")

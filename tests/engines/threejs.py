"""three.js in headless Chromium on SwiftShader: r111 (Debian's libjs-three, WebGL 1) and r180
(the ES module build PyPI's NiceGUI ships, WebGL 2), one harness for both (``release``).

Each call serves one page and its files (three.js, its GLTFLoader, the material under test, the
.glb and any extra files) from a loopback HTTP server on 127.0.0.1 that lives only as long as the
call (ES modules do not load from file://), runs ``chromium --headless --dump-dom`` on it with a
fresh profile, and reads the results the page wrote into ``<pre id="out">``: JSON whose arrays
travel as base64 Float64Array/Uint8Array bytes, so every float arrives bit-exactly. One page runs
a list of jobs, each on its own fresh parse of the .glb, so a test pays one Chromium start for
several renders. Errors thrown by the page (and ``console.error``, where three.js reports shader
compile errors) become a ``RuntimeError`` with the message; the page also checks that
``THREE.REVISION`` is the release asked for.
"""
import base64
import html
import http.server
import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from typing import Callable, NamedTuple

import numpy as np

from . import Shot, ndc_to_pixels

CHROMIUM = "chromium"
CLOCK = "clock"  # served path of the real-time clock (_Files)
# A page's timing functions: now(), the serving process's clock in ms (performance.now() stands
# still under Chromium's virtual time once the page has awaited anything), and overhead, what a
# reading costs (a loopback round trip), for the benches to take off.
CLOCK_JS = """function now() {
    var request = new XMLHttpRequest();
    request.open('GET', '""" + CLOCK + """', false);
    request.send();
    return parseFloat(request.responseText);
  }
  var overhead = Infinity;
  for (var e = 0; e < 10; e++) {
    var before = now();
    overhead = Math.min(overhead, now() - before);
  }"""
TIMEOUT_S = 60
NICEGUI_THREE = os.path.join("elements", "scene", "dist", "index.js")  # inside the nicegui package


class Release(NamedTuple):
    """One three.js release the harness runs."""

    revision: str      # THREE.REVISION
    context: str       # the WebGL context its WebGLRenderer creates
    material: str      # the shipped file of shaders/threejs/ this release loads
    texcoords: tuple   # its GLTFLoader's attribute names for TEXCOORD_0 .. TEXCOORD_7
    installed_by: str


RELEASES = {
    # r111 GLTFLoader: TEXCOORD_1 -> uv2, the others lower-cased.
    "r111": Release("111", "WebGL 1", "boxmarch.js", ("uv", "uv2", *(f"texcoord_{n}" for n in range(2, 8))),
                    "apt-get install chromium libjs-three"),
    # r151 renamed TEXCOORD_1..3 to uv1..uv3; TEXCOORD_4 and up stay lower-cased.
    "r180": Release("180", "WebGL 2", "boxmarch.module.js", ("uv", "uv1", "uv2", "uv3", *(f"texcoord_{n}" for n in range(4, 8))),
                    "apt-get install chromium; pip install nicegui==3.18.0"),
}

_R111_FILES = {"three.min.js": "/usr/share/javascript/three/build/three.min.js",
               "GLTFLoader.js": "/usr/share/javascript/three/examples/js/loaders/GLTFLoader.js"}

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
function __finish(results) {
  document.querySelectorAll('script').forEach(function (s) { s.remove(); });
  document.getElementById('out').textContent = JSON.stringify(__errors.length ? {errors: __errors} : results);
}
// Each job gets its own parse of model.glb (null for a page without a model); a job may return a Promise.
async function __run() {
  var results = [];
  try {
    if (THREE.REVISION !== '__REVISION__') throw new Error('three.js r' + THREE.REVISION + ' loaded, not r__REVISION__');
    var bytes = __HAS_MODEL__ ? await (await fetch('model.glb')).arrayBuffer() : null;
    for (var i = 0; i < __jobs.length; i++) {
      var gltf = bytes && await new Promise(function (resolve, reject) {
        new GLTFLoader().parse(bytes, '', resolve, function (e) { reject(new Error('GLTFLoader: ' + String(e && e.message || e))); });
      });
      results.push(await __jobs[i](gltf));
    }
  } catch (e) { __errors.push(String(e && e.stack || e)); }
  __finish(results);
}
var __jobs = [__JOBS__];
</script>
__LOADERS__
</body></html>"""

# r111: classic scripts (THREE and THREE.GLTFLoader globals); r180: the ES module, whose exports
# the page makes globals so the jobs' JavaScript is the same for both.
_LOADERS = {
    "r111": """<script src="three.min.js"></script><script src="GLTFLoader.js"></script>
<script src="material.js"></script><script>var GLTFLoader = THREE.GLTFLoader; __run();</script>""",
    "r180": """<script type="module">
import { THREE, GLTFLoader } from './three.module.js';
import * as material from './material.js';
window.THREE = THREE; window.GLTFLoader = GLTFLoader; Object.assign(window, material);
__run();
</script>""",
}

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

_RENDER_JOB = """async function (gltf) {
  var W = __W__, H = __H__, cam = __CAMERA__;
  // the page's one renderer (render_job)
  var renderer = window.__pageRenderer || (window.__pageRenderer = new THREE.WebGLRenderer({
    canvas: document.createElement('canvas'), antialias: false, alpha: true, preserveDrawingBuffer: true}));
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
  await (async function (THREE, scene, gltf, camera) {
    __SETUP__
  })(THREE, scene, gltf, camera);
  renderer.render(scene, camera);
  var gl = renderer.getContext(), px = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
  var extra = await (async function (THREE, renderer, scene, camera, W, H) {
    __AFTER__
  })(THREE, renderer, scene, camera, W, H);
  return Object.assign({pixels: __b64(px), view: __f64(camera.matrixWorldInverse.elements),
                        projection: __f64(camera.projectionMatrix.elements)}, extra || {});
}"""

def counting_js(line, counted):
    """``after_js`` for :func:`count_job` counting, per pixel, what every fragment of the shipped
    marching material (and of its eye-box pass, useBoxmarchBackFaceCulling) adds: the material's
    ``line`` becomes ``counted`` (GLSL that writes the fragment's count into gl_FragColor.r and
    returns), drawn with additive blending into a float target, no depth test; the rest of the
    material (the hidden-box pre-pass's returns among it) runs as shipped."""
    return """var marching = [];
    scene.traverse(function (o) {
      if (o.isMesh && o.material.uniforms && o.material.uniforms.bmMarch) marching.push(o.material);
      if (o.userData.boxmarchEyeBox) marching.push(o.userData.boxmarchEyeBox.material);
    });
    marching.forEach(function (m) {
      var text = m.fragmentShader.replace(__LINE__, __COUNTED__);
      if (text === m.fragmentShader) throw new Error('counting: no ' + __LINE__ + ' in the material');
      m.fragmentShader = text;
      m.blending = THREE.AdditiveBlending;
      m.transparent = true;
      m.depthTest = false;
      m.depthWrite = false;
      m.needsUpdate = true;
    });
    var gl = renderer.getContext();
    ['EXT_color_buffer_float', 'EXT_float_blend', 'OES_texture_float', 'WEBGL_color_buffer_float']
      .forEach(function (e) { gl.getExtension(e); });
    var target = new THREE.WebGLRenderTarget(W, H, {type: THREE.FloatType, minFilter: THREE.NearestFilter,
                                                    magFilter: THREE.NearestFilter});
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    var counts = new Float32Array(W * H * 4);
    renderer.readRenderTargetPixels(target, 0, 0, W, H, counts);
    renderer.setRenderTarget(null);
    return {counts: __f64(counts)};""".replace("__LINE__", json.dumps(line)).replace("__COUNTED__", json.dumps(counted))


# The SDF evaluations of every fragment (march steps plus a hit's 3 normal taps), as the Blender
# preview's STEPS output counts them: the line that discards a miss writes the count instead.
_COUNT_AFTER = counting_js("  if (!hit) discard;",
                           "  gl_FragColor = vec4(float(steps + (hit ? normalTaps : 0)), 0.0, 0.0, 1.0);\n  return;")
# The fragments the rasteriser hands the material, before anything in it runs: 1 per fragment.
FRAGMENTS_AFTER = counting_js("void main() {", "void main() {\n  gl_FragColor = vec4(1.0, 0.0, 0.0, 1.0);\n  return;")


# A page function (no model needed) making a BufferGeometry of ``count`` cubes of half-extent 1,
# 3 units apart on a grid 80 cubes wide and deep (cube b at 3 (b % 80, b / 80 % 80, b / 6,400)),
# box numbers 0 .. count - 1 in bmOffsetZIndex.y, each face's 4 corners its own vertices as the
# glTF export splits them, every triangle wound outward, indexed (Uint32): the shape of the export
# that boxmarchClosedOutward reads; ``boxData``: also the attributes boxmarchSealedTriangles reads
# (bmOffsetXY and bmOffsetZIndex.x: f, the box-local vector from the corner to the box's origin;
# bmHalfXY, bmHalfZ: 1).
CUBES_JS = """function boxmarchTestCubes(THREE, count, boxData) {
  var faces = [[0, 1, 2], [0, 2, 1], [1, 2, 0], [1, 0, 2], [2, 0, 1], [2, 1, 0]];  // axis, u, v: + then - side
  var corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]];
  var position = new Float32Array(72 * count), number = new Float32Array(48 * count), index = new Uint32Array(36 * count);
  var offset = new Float32Array(boxData ? 48 * count : 0);
  for (var b = 0; b < count; b++) {
    for (var f = 0; f < 6; f++) {
      var axis = faces[f][0], u = faces[f][1], v = faces[f][2], base = 24 * b + 4 * f;
      for (var k = 0; k < 4; k++) {
        var at = 3 * (base + k);
        position[at + axis] = f % 2 ? -1 : 1;
        position[at + u] = corners[k][0];
        position[at + v] = corners[k][1];
        if (boxData) {
          offset[2 * (base + k)] = -position[at];
          offset[2 * (base + k) + 1] = -position[at + 1];
          number[2 * (base + k)] = -position[at + 2];
        }
        position[at] += 3 * (b % 80);  // 470,000 cubes within 240 units, each 2 across: many float32 steps
        position[at + 1] += 3 * ((b / 80 | 0) % 80);
        position[at + 2] += 3 * (b / 6400 | 0);
        number[2 * (base + k) + 1] = b;
      }
      index.set([base, base + 1, base + 2, base, base + 2, base + 3], 36 * b + 6 * f);
    }
  }
  var geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geometry.setAttribute('bmOffsetZIndex', new THREE.BufferAttribute(number, 2));
  if (boxData) {
    geometry.setAttribute('bmOffsetXY', new THREE.BufferAttribute(offset, 2));
    geometry.setAttribute('bmHalfXY', new THREE.BufferAttribute(new Float32Array(48 * count).fill(1), 2));
    geometry.setAttribute('bmHalfZ', new THREE.BufferAttribute(new Float32Array(24 * count).fill(1), 1));
  }
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  return geometry;
}"""

def shipped_material(release="r111"):
    """The text of the shipped material file the release loads (shaders/threejs/), as it is."""
    from boxmarch.formats import shader_sources

    return (shader_sources.shader_dir() / "threejs" / RELEASES[release].material).read_text()


def _nicegui_three():
    spec = importlib.util.find_spec("nicegui")  # finds the package without importing it
    if spec is None or not spec.submodule_search_locations:
        return None
    return os.path.join(spec.submodule_search_locations[0], NICEGUI_THREE)


def _release_files(release):
    """Served name -> path of the release's three.js files (a path may not exist)."""
    if release == "r111":
        return dict(_R111_FILES)
    return {"three.module.js": _nicegui_three() or "(the nicegui package)/" + NICEGUI_THREE}


def available(release="r111"):
    """None when Chromium and the release's three.js files are installed, else the reason they are not."""
    if shutil.which(CHROMIUM) is None:
        return "chromium is not installed (apt-get install chromium)"
    for path in _release_files(release).values():
        if not os.path.isfile(path):
            return f"{path} is missing ({RELEASES[release].installed_by})"
    return None


class Job(NamedTuple):
    """A JavaScript function of the loaded gltf (its result JSON, or a Promise of it) and what
    turns that result into the Python value :func:`run_jobs` returns."""

    js: str
    parse: Callable = lambda result: result


class _Files(http.server.BaseHTTPRequestHandler):
    files = {}  # served path -> bytes, set per server

    def do_GET(self):
        name = self.path.split("?")[0].lstrip("/")
        # CLOCK: this process's clock in ms, for pages that time themselves: under
        # --virtual-time-budget, performance.now() stands still once the page has awaited anything.
        body = f"{time.perf_counter() * 1e3!r}".encode() if name == CLOCK else self.files.get(name)
        if body is None:
            self.send_error(404)
            return
        kind = {".js": "text/javascript", ".html": "text/html", ".json": "application/json"}
        self.send_response(200)
        self.send_header("Content-Type", kind.get(os.path.splitext(self.path)[1], "application/octet-stream"))
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args):
        pass


def _serve(files):
    """A loopback HTTP server of ``files`` on a free port, in a daemon thread; the caller shuts it down."""
    handler = type("Files", (_Files,), {"files": files})
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def _chromium_temp_base():
    """Where Chromium's temporary folder goes: Chromium puts its singleton socket at
    $TMPDIR/org.chromium.Chromium.XXXXXX/SingletonSocket (46 bytes) and aborts where that path
    passes a Unix socket's 107 bytes; a deep temporary folder (a test's own tmp_path as TMPDIR,
    under pytest-xdist's per-worker folders) gives way to /tmp."""
    base = tempfile.gettempdir()
    return base if len(base) <= 36 else "/tmp"


def chromium(url, *mode, budget_ms=30000, timeout_s=None):
    """(exit code, stdout, stderr) of headless Chromium on SwiftShader, with a fresh profile, run on
    ``url`` in ``mode`` (its flags: ``--dump-dom``, or ``--screenshot=PATH``, ``--window-size=W,H``)
    for at most ``budget_ms`` of the page's virtual time; RuntimeError after ``timeout_s`` (None:
    TIMEOUT_S as it is then, which a bench may raise)."""
    timeout_s = TIMEOUT_S if timeout_s is None else timeout_s
    with tempfile.TemporaryDirectory(prefix="boxmarch-three-", dir=_chromium_temp_base()) as tmp:
        cmd = [CHROMIUM, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
               "--no-proxy-server", f"--virtual-time-budget={budget_ms}", f"--user-data-dir={os.path.join(tmp, 'profile')}",
               *mode, url]
        # own session: on timeout every Chromium process (GPU, renderer) is killed with it
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                                env=dict(os.environ, TMPDIR=tmp))
        try:
            stdout, stderr = proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            raise RuntimeError(f"chromium timed out after {timeout_s} s:\n{proc.communicate()[1][-4000:]}") from None
    return proc.returncode, stdout, stderr


def run_jobs(glb_bytes, jobs, material_js="", release="r111", files=None, timeout_s=None):
    """Runs each :class:`Job` (or plain JS function text) in headless Chromium with three.js
    ``release`` loaded, in order, each on a fresh parse of ``glb_bytes`` (null when it is empty);
    returns their parsed results. ``material_js``: served as material.js, a classic script for
    r111 (its functions become globals) or an ES module for r180 (its exports become globals).
    ``files``: extra served files, name -> bytes (``glb_bytes`` is served as model.glb).
    ``timeout_s``: how long the page may take (None: TIMEOUT_S; a page of many jobs may take more)."""
    jobs = [j if isinstance(j, Job) else Job(j) for j in jobs]
    served = {name: open(path, "rb").read() for name, path in _release_files(release).items()}
    served.update({"material.js": material_js.encode(), "model.glb": bytes(glb_bytes)})
    served.update(files or {})
    parts = {"__REVISION__": RELEASES[release].revision, "__HAS_MODEL__": "true" if glb_bytes else "false",
             "__JOBS__": ",\n".join(j.js for j in jobs), "__LOADERS__": _LOADERS[release]}
    served["page.html"] = re.sub("|".join(parts), lambda m: parts[m.group(0)], _PAGE).encode()
    server = _serve(served)
    try:
        returncode, stdout, stderr = chromium(f"http://127.0.0.1:{server.server_address[1]}/page.html", "--dump-dom",
                                           timeout_s=timeout_s)
    finally:
        server.shutdown()
        server.server_close()
    found = re.search(r'<pre id="out">(.*?)</pre>', stdout, re.S)
    if returncode != 0 or not found or not found.group(1):
        raise RuntimeError(f"chromium (exit {returncode}) wrote no result:\n{stderr[-4000:]}")
    results = json.loads(html.unescape(found.group(1)))
    if isinstance(results, dict) and "errors" in results:
        raise RuntimeError(f"three.js r{RELEASES[release].revision} page failed:\n" + "\n".join(results["errors"]))
    return [job.parse(result) for job, result in zip(jobs, results)]


def run_page(glb_bytes, job_js, material_js="", release="r111"):
    """The result of one job (:func:`run_jobs`)."""
    return run_jobs(glb_bytes, [job_js], material_js, release)[0]


def f64(b64):
    """The float64 array a page sent as base64 bytes (its __f64)."""
    return np.frombuffer(base64.b64decode(b64), dtype=np.float64)


def _meshes(result):
    meshes = []
    for m in result:
        attrs = m["attributes"]
        meshes.append({
            "name": m["name"],
            "attributes": {k: f64(a["data"]).reshape(-1, a["itemSize"]) for k, a in attrs.items()},
            "normalized": {k: a["normalized"] for k, a in attrs.items()},
            "index": None if m["index"] is None else f64(m["index"]),
            "matrixWorld": f64(m["matrixWorld"]).reshape(4, 4, order="F"),
        })
    return meshes


def load_job():
    """:class:`Job` of what the release's GLTFLoader actually put on the GPU side of every mesh.

    Its result: one dict per Mesh/SkinnedMesh in traversal (load) order: ``{"name": str,
    "attributes": {three_name: (count, itemSize) float64 array of the raw BufferAttribute values
    (normalized integer attributes stay raw integers, as getX..getW return them)},
    "normalized": {three_name: bool}, "index": (n,) float64 array or None, "matrixWorld": 4x4}``.
    three_name is the release's: POSITION -> position, NORMAL -> normal, TANGENT -> tangent,
    COLOR_0 -> color, TEXCOORD_n -> ``RELEASES[release].texcoords[n]``.
    """
    return Job(_LOAD_JOB, _meshes)


def load_attributes(glb_bytes, release="r111"):
    """:func:`load_job`'s result for ``glb_bytes`` (one page)."""
    return run_jobs(glb_bytes, [load_job()], release=release)[0]


def render_job(setup_js, width, height, camera, after_js="return {};"):
    """:class:`Job` rendering the loaded .glb once (WebGL 1 for r111, WebGL 2 for r180; SwiftShader);
    its result is a :class:`Shot`.

    ``setup_js``: the body of an async function of ``THREE``, ``scene``, ``gltf`` and ``camera``
    (``await`` allowed; ``GLTFLoader`` and the material file's functions are globals), typically
    replacing mesh materials; ``gltf.scene`` is already in ``scene``.
    ``camera``: ``{"position", "target", "up" (default +Y), "fov" (vertical degrees)}`` for a
    PerspectiveCamera or ``{"ortho": half_height, ...}`` for an OrthographicCamera with the
    image's aspect; optional ``near`` (0.1) and ``far`` (1000). The clear colour is (0, 0, 0, 0).
    ``Shot.view`` is ``camera.matrixWorldInverse`` and ``Shot.to_pixels`` comes from
    ``camera.projectionMatrix``, both as three.js computed them. ``after_js``: the body of an
    async function of ``THREE``, ``renderer``, ``scene``, ``camera``, ``W`` and ``H`` run after
    the render; what it returns joins the job's raw result (see :func:`count_job`).
    Every render job of a page draws with the page's one WebGLRenderer, as an app draws every scene
    with one renderer, its compiled programs kept (SwiftShader takes seconds to compile a marching
    material: a page of 24 pictures drew 2.7x faster so than with a renderer a job, every pixel the
    same).
    """
    js = (_RENDER_JOB.replace("__W__", str(int(width))).replace("__H__", str(int(height)))
          .replace("__CAMERA__", json.dumps(camera)).replace("__SETUP__", setup_js).replace("__AFTER__", after_js))

    def shot(out):
        pixels = np.frombuffer(base64.b64decode(out["pixels"]), dtype=np.uint8)
        pixels = pixels.reshape(height, width, 4)[::-1].copy()  # readPixels starts at the bottom row
        view = f64(out["view"]).reshape(4, 4, order="F")
        projection = f64(out["projection"]).reshape(4, 4, order="F")
        return Shot(pixels, view, ndc_to_pixels(width, height) @ projection @ view)

    return Job(js, shot)


def count_job(setup_js, width, height, camera, counting_js=_COUNT_AFTER):
    """:class:`Job` rendering as :func:`render_job` does, then counting the SDF evaluations of
    every fragment of the shipped marching material (_COUNT_AFTER; ``counting_js``: another
    ``after_js`` returning ``{counts: __f64(W x H x 4 floats, the count in the first)}``); its
    result is ``(Shot, evaluations)``, evaluations a (height, width) float array, row 0 at the top."""
    job = render_job(setup_js, width, height, camera, counting_js)

    def parse(out):
        counts = f64(out["counts"]).reshape(height, width, 4)[::-1, :, 0].copy()
        return job.parse(out), counts

    return Job(job.js, parse)


def render(glb_bytes, material_js, setup_js, width, height, camera, release="r111"):
    """One :func:`render_job` in its own page: a :class:`Shot`."""
    return run_jobs(glb_bytes, [render_job(setup_js, width, height, camera)], material_js, release)[0]


def pose_bones_js(turns, angle):
    """JavaScript for :func:`render`'s ``setup_js``: turns each bone named in ``turns`` (name ->
    world axis (3,) as the axis points with the skeleton at rest) by ``angle`` radians (or
    ``angle[name]``, a dict giving each bone its own) about its own head, on top of its rest
    rotation, so it carries the bones below it. The axis is moved into the bone's local frame
    with the bones' rest world rotations, read before any turn."""
    angles = {name: float(angle[name] if isinstance(angle, dict) else angle) for name in turns}
    return ("gltf.scene.updateMatrixWorld(true);\n"
            f"var bmTurns = {json.dumps({k: [float(x) for x in v] for k, v in turns.items()})}, bmRest = {{}};\n"
            f"var bmAngles = {json.dumps(angles)};\n"
            "Object.keys(bmTurns).forEach(function (name) {\n"
            "  var bone = gltf.scene.getObjectByName(name);\n"
            "  if (!bone || !bone.isBone) throw new Error('no bone named ' + name);\n"
            "  bmRest[name] = bone.getWorldQuaternion(new THREE.Quaternion());\n"
            "});\n"
            "Object.keys(bmTurns).forEach(function (name) {\n"
            "  var back = bmRest[name].clone(); back = back.invert ? back.invert() : back.inverse();  // r123 renamed it\n"
            "  var axis = new THREE.Vector3().fromArray(bmTurns[name]).normalize().applyQuaternion(back);\n"
            "  gltf.scene.getObjectByName(name).quaternion.multiply(new THREE.Quaternion().setFromAxisAngle(axis, bmAngles[name]));\n"
            "});\n"
            "gltf.scene.updateMatrixWorld(true);\n")

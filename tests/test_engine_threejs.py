"""Proof in real engines: the GLTF preset's .glb loaded unmodified by three.js r111 (Debian's,
WebGL 1) and r180 (NiceGUI's ES module build, WebGL 2) GLTFLoaders in headless Chromium. The test
decodes what three.js put in its buffers with the documented formula (docs/ENGINES.md) and checks
it against the generating box geometry; then the shipped material (shaders/threejs/, unmodified,
the release's file: a ShaderMaterial on r111, on r180 a RawShaderMaterial declaring its depth)
raymarches every box and the pixels must cover each box's
projected silhouette within 1 px. Negative controls (a channel zeroed, the frame replaced by the
identity) must fail the same checks. The one-call loader (loadBoxmarch) draws the same file from
its URL and sidecar, and refuses a sidecar it does not read. One Chromium page per release runs
every render of this file (module-scoped ``page``)."""
import json
import subprocess

import numpy as np
import pytest

from tests.conftest import empty_scene
from tests.engine_scene import (
    MIXED_SHAPES,
    TO_Y_UP,
    baked_scene,
    box_of_vertex,
    decode_normal_frame,
    frame_and_size_errors,
    paint_shapes,
    per_box_agreement,
    rounded_box_mismatch,
    silhouettes,
)
from tests.engines import coverage_mismatch, threejs
from tests.helpers.glsl import preprocessed
from tests.helpers.preview_render import EXACT_MARCH
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 320, 240
WIDE = {"position": [2.0, 9.0, 14.0], "target": [0.5, -0.5, 0.0], "fov": 50, "near": 0.5, "far": 100}
# The far plane leaves only the three 0.02 x 0.02 x 0.1 boxes (numbers 3-5) in this view.
CLOSE = {"position": [0.12, 0.2, 0.3], "target": [0.0, 0.0, 0.0], "fov": 30, "near": 0.01, "far": 0.6}
CAMERAS = {"all-boxes": (WIDE, slice(None)), "close-up-on-0.02-boxes": (CLOSE, slice(3, 6))}
# A box at 0.6 of each box's half-extents about its decoded origin: unlike the full box, which
# the rasterised mesh already outlines, it lands right only if origin, axes and extents do.
BOX_MAP = "return sd_box(p, 0.6 * box_half);"
INNER = 0.6
ROUNDED_MAP = "return sd_round_box(p, box_half, 0.1 * min3(box_half));"
IDENTITY_FRAME = ("var n = g.getAttribute('normal').array, t = g.getAttribute('tangent').array;"
                  "for (var i = 0; i < n.length / 3; i++) { n.set([0, 0, 1], 3 * i); t.set([1, 0, 0, 1], 4 * i); }")
PER_BOX_MAP = "return bm_sdf_by_id(box_params.x, p, box_half);"
# The same shapes as a map() of the user's own (not a preset's text): marched.
PER_BOX_USER_MAP = "return 1.0 * bm_sdf_by_id(box_params.x, p, box_half);"
pytestmark = pytest.mark.slow


def offset_zeroed(release):
    """Negative control: the offset channels (TEXCOORD_1 and _2 under the release's names) zeroed."""
    names = threejs.RELEASES[release].texcoords
    return f"g.getAttribute('{names[1]}').array.fill(0); g.getAttribute('{names[2]}').array.fill(0);"


def setup_js(sdf_body, tamper=""):
    """Gives every mesh the shipped material; ``tamper`` (JS, with ``g`` the geometry) runs first."""
    return (f"gltf.scene.traverse(function (o) {{ if (!o.isMesh) return; var g = o.geometry; {tamper}\n"
            f"useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {{map: {json.dumps(sdf_body)}, "
            f"color: new THREE.Color(1, 1, 1), maxSteps: 256}})); }});")


def loader_setup_js(name, sdf_body, front_to_back=False, declare_depth=True, url_tail=""):
    """Draws ``name``.glb as ``loadBoxmarch`` loads it (in place of the page's own parse);
    ``declare_depth`` False: the ShaderMaterial without the depth declaration on r163+ too;
    ``url_tail``: a query and fragment after the file name in the URL."""
    return (f"scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, '{name}.glb{url_tail}', "
            f"{{map: {json.dumps(sdf_body)}, color: new THREE.Color(1, 1, 1), maxSteps: 256, "
            f"frontToBack: {json.dumps(front_to_back)}, declareDepth: {json.dumps(declare_depth)}}});"
            " scene.add(loaded.scene); if (!loaded.meshes.length) throw new Error('loadBoxmarch: no meshes');"
            " if (!!loaded.meshes[0].material.isRawShaderMaterial !== (parseInt(THREE.REVISION, 10) >= 163 && "
            f"{json.dumps(declare_depth)})) throw new Error('not the material asked for');")


def refusal_job(js):
    """A job whose result is the message of the error ``js`` (a Promise or a statement) raises, or 'no error'."""
    return ("async function (gltf) { try { await (async function () { " + js + " })(); return 'no error'; }"
            " catch (e) { return String(e && e.message || e); } }")


# The index buffers of mixed.glb as the file has it (the job's own parse) and after loadBoxmarch's
# frontToBack sorted it for the WIDE camera (two frames drawn: r111 uploads the sorted buffer at
# the second), and whether a second sort for the same eye did anything.
SORT_JOB = """async function (gltf) {
  var loaded = await loadBoxmarch(THREE, GLTFLoader, 'mixed.glb', {frontToBack: true});
  var cam = __CAMERA__, camera = new THREE.PerspectiveCamera(cam.fov, __W__ / __H__, cam.near, cam.far);
  camera.position.fromArray(cam.position);
  camera.lookAt(new THREE.Vector3().fromArray(cam.target));
  var renderer = new THREE.WebGLRenderer({canvas: document.createElement('canvas')});
  renderer.setSize(__W__, __H__, false);
  var scene = new THREE.Scene();
  scene.add(loaded.scene);
  renderer.render(scene, camera);
  renderer.render(scene, camera);
  renderer.dispose();
  renderer.forceContextLoss();
  var file = null;
  gltf.scene.traverse(function (o) { if (o.isMesh) file = o.geometry.index.array; });
  var mesh = loaded.meshes[0];
  return {file: __f64(file), sorted: __f64(mesh.geometry.index.array),
          sorted_again: sortBoxmarchFrontToBack(THREE, mesh, camera)};
}""".replace("__CAMERA__", json.dumps(WIDE)).replace("__W__", str(W)).replace("__H__", str(H))


# The shipped material's stages as the release's three.js hands them to WebGL (the page's first
# mesh drawn with createBoxmarchMaterial's defaults from outside its boxes, shaderSource recorded
# (``stagesOutside``: how many), then from inside its first box, where its eye-box variant's come,
# drawn right after: useBoxmarchEyeBox), the context's
# requests for EXT_conservative_depth among them ("getExtension" in ``calls``, in order with
# "vertex" and "fragment"), whether the context offers the extension, and on WebGL 2 what its
# compiler (ANGLE) says of the fragment text as built and with depth_greater misspelled, on a
# context that handed the extension out and on one that did not ('ok' or the compile log).
STAGES_JOB = """function (gltf) {
  var sources = [], calls = [], prototypes = [WebGLRenderingContext.prototype];
  if (typeof WebGL2RenderingContext !== 'undefined') prototypes.push(WebGL2RenderingContext.prototype);
  var originals = prototypes.map(function (p) { return {shaderSource: p.shaderSource, getExtension: p.getExtension}; });
  prototypes.forEach(function (p, i) {
    p.shaderSource = function (shader, text) {
      sources.push(text);
      calls.push(calls.indexOf('vertex') < 0 ? 'vertex' : 'fragment');
      return originals[i].shaderSource.call(this, shader, text);
    };
    p.getExtension = function (name) {
      if (name === 'EXT_conservative_depth') calls.push('getExtension');
      return originals[i].getExtension.call(this, name);
    };
  });
  var renderer = new THREE.WebGLRenderer({canvas: document.createElement('canvas')}), outside = null;
  try {
    renderer.setSize(64, 64, false);
    var mesh = null;
    gltf.scene.traverse(function (o) { if (o.isMesh && !mesh) mesh = o; });
    useBoxmarchMaterial(THREE, mesh, createBoxmarchMaterial(THREE));
    var camera = new THREE.PerspectiveCamera(50, 1, 0.1, 100);
    camera.position.set(0, 0, 20);
    var scene = new THREE.Scene();
    scene.add(mesh);
    renderer.render(scene, camera);
    outside = sources.length;
    // the eye at the centre of the first vertex's box (the mean of its corners): the eye-box variant draws
    var number = mesh.geometry.getAttribute('bmOffsetZIndex'), position = mesh.geometry.getAttribute('position');
    var centre = new THREE.Vector3(), corner = new THREE.Vector3(), corners = 0;
    for (var v = 0; v < position.count; v++) {
      if (number.getY(v) === number.getY(0)) { centre.add(corner.fromBufferAttribute(position, v)); corners++; }
    }
    camera.position.copy(centre.divideScalar(corners).applyMatrix4(mesh.matrixWorld));
    renderer.render(scene, camera);
  } finally {
    prototypes.forEach(function (p, i) { p.shaderSource = originals[i].shaderSource; p.getExtension = originals[i].getExtension; });
  }
  var gl = renderer.getContext(), webgl2 = typeof WebGL2RenderingContext !== 'undefined' && gl instanceof WebGL2RenderingContext;
  var result = {vertex: sources[0], fragment: sources[1], eyeFragment: sources[3] || null, stages: sources.length, stagesOutside: outside,
                calls: calls, webgl2: webgl2,
                extension: (gl.getSupportedExtensions() || []).indexOf('EXT_conservative_depth') >= 0, angle: null};
  renderer.dispose();
  renderer.forceContextLoss();
  if (!webgl2) return result;
  function compile(context, text) {
    var shader = context.createShader(context.FRAGMENT_SHADER);
    context.shaderSource(shader, text);
    context.compileShader(shader);
    var log = context.getShaderParameter(shader, context.COMPILE_STATUS) ? 'ok' : context.getShaderInfoLog(shader);
    context.deleteShader(shader);
    return log;
  }
  var misspelled = result.fragment.replace('layout(depth_greater)', 'layout(depth_greatr)');
  var handedOut = document.createElement('canvas').getContext('webgl2'), withheld = document.createElement('canvas').getContext('webgl2');
  result.angle = {handed_out: !!handedOut.getExtension('EXT_conservative_depth'),
                  as_built: compile(handedOut, result.fragment), misspelled: compile(handedOut, misspelled),
                  withheld_as_built: compile(withheld, result.fragment), withheld_misspelled: compile(withheld, misspelled)};
  [handedOut, withheld].forEach(function (c) { c.getExtension('WEBGL_lose_context').loseContext(); });
  return result;
}"""


def covered(shot):
    return shot.pixels[..., 3] > 0


@pytest.fixture(scope="module")
def exported(bpy_module, tmp_path_factory):
    """The mixed scene exported with the GLTF preset (NORMAL_FRAME) and with layout CLASSIC."""
    blender = empty_scene(bpy_module)
    ob, centres, sizes, rotations = baked_scene(blender)
    files = {"baked_boxes": paint_shapes(blender, ob, MIXED_SHAPES)}
    for layout in ("NORMAL_FRAME", "CLASSIC"):
        path = tmp_path_factory.mktemp("threejs") / f"{layout}.glb"
        assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF", layout=layout) == {"FINISHED"}
        files[layout] = path.read_bytes()
        files[layout, "sidecar"] = path.with_suffix(".boxmarch.json").read_bytes()  # as the export wrote it
    return files, centres, sizes, rotations


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def page(request, exported):
    """One page per release: {"release", "meshes", (map, camera name) -> Shot, tamper name -> Shot,
    "loader" -> Shot, refusal name -> message}, and the scene's boxes."""
    release = request.param
    need(threejs.available(release))
    files, centres, sizes, rotations = exported
    glb = files["NORMAL_FRAME"]
    served = {"mixed.glb": glb, "mixed.boxmarch.json": files["NORMAL_FRAME", "sidecar"],
              "classic-layout.glb": files["CLASSIC"],
              "classic.boxmarch.json": files["CLASSIC", "sidecar"],
              "future.boxmarch.json": json.dumps({**json.loads(files["NORMAL_FRAME", "sidecar"]),
                                                  "format_version": 2}).encode()}
    jobs = {"meshes": threejs.load_job()}
    for sdf in (BOX_MAP, ROUNDED_MAP):
        for name, (camera, _view) in CAMERAS.items():
            jobs[sdf, name] = threejs.render_job(setup_js(sdf), W, H, camera)
    for name, tamper in (("offset-zeroed", offset_zeroed(release)), ("identity-frame", IDENTITY_FRAME)):
        jobs[name] = threejs.render_job(setup_js(BOX_MAP, tamper), W, H, WIDE)
    jobs["loader"] = threejs.render_job(loader_setup_js("mixed", BOX_MAP), W, H, WIDE)
    jobs["loader-query"] = threejs.render_job(loader_setup_js("mixed", BOX_MAP, url_tail="?v=2#view"), W, H, WIDE)
    jobs["loader-front-to-back"] = threejs.render_job(loader_setup_js("mixed", BOX_MAP, True), W, H, WIDE)
    jobs["sort"] = threejs.Job(SORT_JOB, lambda out: {k: threejs.f64(v) if isinstance(v, str) else v
                                                       for k, v in out.items()})
    jobs["per-box"] = threejs.render_job(setup_js(PER_BOX_MAP), W, H, WIDE)
    jobs["per-box-close"] = threejs.render_job(setup_js(PER_BOX_MAP), W, H, CLOSE)
    jobs["per-box-user-close"] = threejs.render_job(setup_js(PER_BOX_USER_MAP), W, H, CLOSE)
    jobs["loader-undeclared"] = threejs.render_job(loader_setup_js("mixed", BOX_MAP, declare_depth=False), W, H, WIDE)
    jobs["stages"] = threejs.Job(STAGES_JOB)
    # classic.glb and future.glb are not served: a refusal that fetched the .glb would say 404 instead
    for name in ("classic", "future", "missing"):
        jobs[f"refuse-{name}"] = refusal_job(f"await loadBoxmarch(THREE, GLTFLoader, '{name}.glb', {{}});")
    jobs["material-on-classic"] = refusal_job(
        "var g = await new Promise(function (ok, no) { new GLTFLoader().load('classic-layout.glb', ok, undefined, no); });"
        " g.scene.traverse(function (o) { if (o.isMesh) useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE)); });")
    results = threejs.run_jobs(glb, list(jobs.values()), threejs.shipped_material(release), release, served)
    return dict(zip(jobs, results), release=release, baked_boxes=files["baked_boxes"]), centres, sizes, rotations


def test_threejs_receives_every_channel_and_decodes_to_the_boxes(page):
    out, centres, sizes, rotations = page
    (mesh,) = out["meshes"]
    a = mesh["attributes"]
    t = threejs.RELEASES[out["release"]].texcoords  # TEXCOORD_n as this release names them
    assert set(a) == {"position", "normal", "tangent", *t[:8]}  # NORMAL_FRAME writes TEXCOORD_0 .. 7
    assert not any(mesh["normalized"].values())
    box = box_of_vertex(a["position"], centres, sizes, rotations, TO_Y_UP)
    offset = np.concatenate([a[t[1]], a[t[2]][:, :1]], axis=1)
    half = np.concatenate([a[t[3]], a[t[4]][:, :1]], axis=1)
    origins, axes, half = decode_normal_frame(a["position"], a["normal"], a["tangent"], offset, half)
    origin_error, axis_error, half_error = frame_and_size_errors(origins, axes, half, box, centres, sizes,
                                                                 rotations, TO_Y_UP)
    assert origin_error < 1e-5 and axis_error < 1e-6 and half_error < 1e-5, (origin_error, axis_error, half_error)
    index = a[t[2]][:, 1]
    assert np.array_equal(index, np.rint(index))
    for b in range(len(centres)):  # one number per box, a different one for every box
        assert len(set(index[box == b])) == 1
    assert len(set(index)) == len(centres) and set(index) == set(range(len(centres)))


@pytest.mark.parametrize("camera", sorted(CAMERAS))
def test_threejs_raymarches_each_box_where_the_decode_puts_it(page, camera):
    out, centres, sizes, rotations = page
    shot = out[BOX_MAP, camera]
    view = CAMERAS[camera][1]
    expected = silhouettes(shot, centres[view], INNER * sizes[view], rotations[view], TO_Y_UP)
    mismatch = coverage_mismatch(covered(shot), expected)
    assert mismatch is None, mismatch
    assert covered(shot).sum() > 500


def test_threejs_rounded_boxes_lie_between_the_box_and_its_core(page):
    """Rounded boxes of radius r = 0.1 x the smallest half-extent: every covered pixel within 1 px
    of the box, every pixel of the box shrunk by r (the core) covered."""
    out, centres, sizes, rotations = page
    for camera, (_camera, view) in CAMERAS.items():
        shot = out[ROUNDED_MAP, camera]
        mismatch = rounded_box_mismatch(covered(shot), shot, centres[view], sizes[view], rotations[view], TO_Y_UP)
        assert mismatch is None, (camera, mismatch)


def test_threejs_draws_the_shape_each_box_id_picks(page):
    """Each box drawn with the preset its painted shape id picks (TEXCOORD_5.x through
    bm_sdf_by_id): the coverage matches the CPU reference drawing the same ids on >= 99.5% of
    pixels; against the ids shuffled (rolled by one box) it must not."""
    out, _centres, _sizes, _rotations = page
    shot = out["per-box"]
    agree = per_box_agreement(covered(shot), shot, WIDE, out["baked_boxes"], MIXED_SHAPES)
    shuffled = per_box_agreement(covered(shot), shot, WIDE, out["baked_boxes"], np.roll(MIXED_SHAPES, 1))
    assert covered(shot).sum() > 500
    assert agree >= 0.995 and shuffled < 0.99, (agree, shuffled)


def test_threejs_presets_hit_in_closed_form_and_a_users_map_marches(page):
    """The per-box presets (bm_sdf_by_id's text: solved in closed form, boxmarchClosedForm), close
    up on the 0.02 boxes, cover what the CPU reference marched to the exact surface covers on every
    pixel but a few ties (<= 1 in 4,000) and fewer than half the pixels the same shapes miss as a
    user's map() (marched at the material's epsilon 1e-4, 256 steps: its epsilon fattens them)."""
    out, _centres, _sizes, _rotations = page
    shots = [out["per-box-close"], out["per-box-user-close"]]
    mismatched = [int(round((1.0 - per_box_agreement(covered(shot), shot, CLOSE, out["baked_boxes"], MIXED_SHAPES,
                                                     **EXACT_MARCH)) * W * H)) for shot in shots]
    assert covered(shots[0]).sum() > 2000
    assert mismatched[0] <= W * H / 4000 and mismatched[0] < 0.5 * mismatched[1], mismatched


@pytest.mark.parametrize("tamper", ["offset-zeroed", "identity-frame"])
def test_threejs_negative_controls_fail(page, tamper):
    out, centres, sizes, rotations = page
    shot = out[tamper]
    assert covered(shot).sum() > 500  # it drew, in the wrong places
    assert coverage_mismatch(covered(shot), silhouettes(shot, centres, INNER * sizes, rotations, TO_Y_UP)) is not None


def test_load_boxmarch_draws_the_export_from_its_url(page):
    """loadBoxmarch(THREE, GLTFLoader, 'mixed.glb', ...) reads mixed.boxmarch.json, loads the file
    and sets the material: the same 1 px check as the material set by hand."""
    out, centres, sizes, rotations = page
    shot = out["loader"]
    mismatch = coverage_mismatch(covered(shot), silhouettes(shot, centres, INNER * sizes, rotations, TO_Y_UP))
    assert mismatch is None, mismatch
    assert covered(shot).sum() > 500
    # a cache-busting query and a fragment: the sidecar is mixed.boxmarch.json?v=2, the same picture
    assert np.array_equal(out["loader-query"].pixels, shot.pixels)


def boxes_in_draw_order(index, positions, centres, sizes, rotations):
    """The generating box of each triangle of ``index``, in order."""
    return box_of_vertex(positions, centres, sizes, rotations, TO_Y_UP)[index[::3].astype(int)]


def test_front_to_back_sort_draws_the_nearest_box_first_and_the_same_image(page):
    """loadBoxmarch's frontToBack: the index buffer holds each box's triangles together, boxes in
    the order of their centres' distance to the camera (the generating geometry's); the file's own
    order is not that (the control); the image is the unsorted one; the same eye sorts nothing."""
    out, centres, sizes, rotations = page
    (mesh,) = out["meshes"]
    assert np.allclose(mesh["matrixWorld"], np.eye(4))
    positions = mesh["attributes"]["position"]
    distance = np.linalg.norm(centres @ TO_Y_UP.T - WIDE["position"], axis=1)
    drawn = boxes_in_draw_order(out["sort"]["sorted"], positions, centres, sizes, rotations)
    assert np.array_equal(np.sort(out["sort"]["sorted"]), np.sort(out["sort"]["file"]))  # the same triangles
    groups = drawn[np.r_[True, drawn[1:] != drawn[:-1]]]
    assert np.array_equal(groups, np.argsort(distance))  # one group per box, nearest first
    in_file = boxes_in_draw_order(out["sort"]["file"], positions, centres, sizes, rotations)
    assert not np.all(np.diff(distance[in_file]) >= 0)
    assert out["sort"]["sorted_again"] is False
    assert np.array_equal(out["loader-front-to-back"].pixels, out["loader"].pixels)


def test_load_boxmarch_refuses_a_sidecar_it_does_not_read(page):
    out = page[0]
    assert out["refuse-classic"] == ('boxmarch: classic.boxmarch.json: layout must be one of NORMAL_FRAME (what this '
                                     'material reads), not "CLASSIC": export with the GLTF preset and its default layout')
    assert out["refuse-future"] == ("boxmarch: future.boxmarch.json: format_version must be 1 (the format this material "
                                    "reads), not 2")
    assert out["refuse-missing"].startswith("boxmarch: no missing.boxmarch.json (HTTP 404)")


def test_material_refuses_a_classic_export(page):
    # CLASSIC holds TEXCOORD_1..5 (frame, then the box parameters): the first one missing is 6
    assert "no TEXCOORD_6" in page[0]["material-on-classic"]


def test_raw_material_draws_the_shader_materials_picture(page):
    """On r180 loadBoxmarch's default is the RawShaderMaterial declaring layout(depth_greater);
    declareDepth false gives the ShaderMaterial: the same pixels, bit for bit (r111: both are the
    ShaderMaterial)."""
    out = page[0]
    assert covered(out["loader"]).sum() > 500
    assert np.array_equal(out["loader-undeclared"].pixels, out["loader"].pixels)


def glslang(tmp_path, text):
    """glslangValidator's (return code, output) for a fragment text."""
    from tests.helpers.glsl import validator

    path = tmp_path / "threejs.frag"
    path.write_text(text)
    proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
    return proc.returncode, proc.stdout + proc.stderr


def test_webgl2_fragment_declares_depth_greater_where_the_extension_is_handed_out(page, tmp_path):
    """The fragment text three.js r180 hands WebGL 2: #version 300 es, then only #define lines
    before the #extension line, the declaration under #ifdef GL_EXT_conservative_depth. ANGLE
    (Chromium's compiler, on SwiftShader, which offers the extension; the material asked the
    renderer's context for it before compiling) compiles it; with
    depth_greater misspelled it refuses it on a context that handed the extension out (so the
    declared branch is compiled) and compiles it on one that did not (the branch left out).
    glslangValidator compiles it as GLSL ES 3.00: Debian's glslang 12 does not know
    GL_EXT_conservative_depth for ES, warns and leaves the branch out (ANGLE compiled it above);
    negative control: the declaration without its #extension line and #ifdef must fail there (no
    depth layout in plain ES 3.00). r111 (WebGL 1): the ShaderMaterial, no #extension line."""
    out = page[0]
    stages = out["stages"]
    assert "bmEye" in stages["fragment"]
    # the eye-box variant on every release (useBoxmarchMaterial: the box holding the eye drawn
    # apart and last, with the cuts and without, so a depth tie at the near plane goes to one box),
    # drawn and compiled only once the eye is in a box (boxmarchEyeMayBeInABox)
    assert stages["stagesOutside"] == 2 and stages["stages"] == 4 and "bmEye" in stages["eyeFragment"]
    if out["release"] == "r111":
        assert not stages["webgl2"] and "conservative_depth" not in stages["fragment"]
        assert "getExtension" not in stages["calls"]
        return
    # the eye-box variant (its march from the eye writes its hit's depth, nearer than its fragment) declares none
    def as_compiled(fragment):  # on a context that hands GL_EXT_conservative_depth out
        return preprocessed(fragment.replace("#ifdef GL_EXT_conservative_depth", "#if 1"))

    assert "depth_greater" in as_compiled(stages["fragment"]) and "depth_greater" not in as_compiled(stages["eyeFragment"])
    lines = stages["fragment"].splitlines()
    assert lines[0] == "#version 300 es"
    extension = lines.index("#extension GL_EXT_conservative_depth : enable")
    assert all(line.startswith("#define ") for line in lines[1:extension])
    declared = lines.index("layout(depth_greater) out highp float gl_FragDepth;")
    assert lines[declared - 1] == "#ifdef GL_EXT_conservative_depth"
    assert lines[declared + 1:declared + 3] == ["#define BM_DEPTH_GREATER", "#endif"]
    assert stages["extension"] is True  # SwiftShader's WebGL 2 offers it: the declared branch runs here
    # the material's onBeforeCompile asked the renderer's context for it before the stages were compiled
    assert stages["calls"][:3] == ["getExtension", "vertex", "fragment"], stages["calls"]
    angle = stages["angle"]
    assert angle["handed_out"] is True
    assert angle["as_built"] == "ok" and angle["withheld_as_built"] == "ok", angle
    assert "depth_greatr" in angle["misspelled"], angle
    assert angle["withheld_misspelled"] == "ok", angle
    code, log = glslang(tmp_path, stages["fragment"])
    assert code == 0, log
    unguarded = [line for k, line in enumerate(lines) if k not in (extension, declared - 1, declared + 1)]
    code, log = glslang(tmp_path, "\n".join(unguarded) + "\n")
    assert code != 0 and "depth layout qualifier" in log, log

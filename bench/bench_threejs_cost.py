"""three.js frame times on SwiftShader with and without the GPU-side techniques, in one run.

The chain down the arm, the pile of links of bench_gpu_cost.py and a pile of 1,000 plain boxes
(bench_gpu_cost.pile_of_boxes), baked and exported with the GLTF preset, loaded by the shipped
loadBoxmarch (shaders/threejs/, r180 on WebGL 2 and r111 on WebGL 1, headless Chromium on
SwiftShader through tests/engines/threejs.py) once per configuration, each in its own scene, and
drawn from bench_gpu_cost's camera. Every configuration is loadBoxmarch with the options its row
names and nothing else: the march's settings are the material's defaults (maxSteps 96, epsilon
1e-4, quality 1), the map the links' preset for the links and the loader's default map (a
rounded box) for the plain boxes. Timed from render() to a 1-pixel readPixels (which waits for the
frame) on the serving process's clock less one reading's round trip (*clock ms*), round robin over
the configurations, best of REPEATS frames each. Rows (CONFIGS):

* none: both sides of every box, no hidden-box pre-pass (``cullBackFaces: false, occluders:
  false``); the speed-ups are against this row;
* default: loadBoxmarch with no options: back faces culled where the boxes are closed and wound
  outward (useBoxmarchBackFaceCulling) and the hidden-box pre-pass (useBoxmarchOccluders) where
  the boxes lie 2 layers deep or more over the view (*pre-pass ran*: whether it did);
* default, marched: the default with the map written as a user's own (``1.0 *`` the preset's
  text) and the pre-pass's occluders named, so the material marches it (96 steps, epsilon 1e-4)
  where the rows above solve the preset in closed form: the cost before closed-form hits;
* culling only (``occluders: false``); pre-pass only (``cullBackFaces: false``);
* default, pre-pass at any depth: the default with the pre-pass's minLayers set to 0, as the
  loader drew it before it measured the depth;
* visibility passes (``visibilityPass: true``, useBoxmarchVisibility: marching passes that write
  no depth, so the depth test culls hidden fragments before they run); its evaluations are both
  passes' (PASSES_COUNT_AFTER);
* front to back (``frontToBack: true``; the camera stands still, so the boxes are sorted once,
  before the timed frames);
* quality 0.5 (the quality knob; no pre-pass below full quality for a marched map; the presets,
  solved in closed form, ignore the knob and keep it);
* r180 only, the ShaderMaterial without the depth declaration (``declareDepth: false``), none:
  what the declaration changes, same scenes, same run.

SDF evaluations per covered pixel: counted in the shader (tests/engines/threejs.py count_job: every
fragment's march steps plus a hit's normal taps, a closed-form hit counting 1, summed through an
additive float target) over the pixels the shaded image covers, one page per configuration after
the timed page.

Pixels changed: pixels whose colour differs from the first row's by more than 1/255, as a share of the
pixels covered in either image. *sort ms*: one sortBoxmarchFrontToBack after the eye moved (mean
of 20). PIECES: parts of a frame timed in the same round robin (a second table).

    PYTHONPATH=addon python3 -m bench.bench_threejs_cost [pile ...]   # PyPI bpy for the bake and the export;
                                                                      # scenes' names: those scenes only
"""
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

SIZE, REPEATS = 320, 7
SCENES = ("chain down the arm", "pile", "pile of boxes")
# the map of each scene's shape: the links' preset; None, the loader's default map (a rounded box)
MAPS = {"LINK": "return sdf_preset_link(p, box_half);", "BOX": None}
# the same shapes as a map() of the user's own, which the material marches (the presets are solved
# in closed form, shaders/glsl/raymarch.glsl bm_preset_hit), with the pre-pass's occluders named
MARCHED = {"LINK": ("return 1.0 * sdf_preset_link(p, box_half);", "LINK"),
           "BOX": ("return 1.0 * sd_round_box(p, box_half, 0.1 * min3(box_half));", "ROUNDED_BOX")}
# label, loadBoxmarch's options (the map added), whether the pre-pass runs at any depth (minLayers 0)
CONFIGS = (("none (cullBackFaces: false, occluders: false)", {"cullBackFaces": False, "occluders": False}, False),
           ("default (no options)", {}, False),
           ("default, marched (the map as a user's own)", {"marched": True}, False),
           ("culling only (occluders: false)", {"occluders": False}, False),
           ("pre-pass only (cullBackFaces: false)", {"cullBackFaces": False}, False),
           ("default, pre-pass at any depth", {}, True),
           ("visibility passes (visibilityPass: true)", {"visibilityPass": True}, False),
           ("front to back (frontToBack: true)", {"frontToBack": True}, False),
           ("quality 0.5", {"quality": 0.5}, False),
           ("ShaderMaterial (declareDepth: false), none",
            {"declareDepth": False, "cullBackFaces": False, "occluders": False}, False))
HEADERS = ["scene", "three.js", "options", "declared", "pre-pass ran", "SDF evals/px", "frame ms", "speed-up",
           "pixels changed", "covered", "sort ms", "clock ms"]
FRONT_TO_BACK = 7  # the row whose sort is timed
FORCED = 5  # the row whose pre-pass is also timed alone (PIECES)
# Pieces of a frame timed in the same round robin: an empty scene (what render() and the read-back
# cost with nothing to draw), the box mesh with three.js's MeshBasicMaterial (front faces; both
# sides), i.e. the rasterisation of the boxes with a trivial fragment stage, and the pre-pass alone
# (its occluder draws, culled, into the canvas)
PIECES = ("empty scene", "boxes, MeshBasicMaterial, front faces", "boxes, MeshBasicMaterial, both sides",
          "the pre-pass alone (its occluder draws)")

TIMING_JOB = """async function (gltf) {
  var W = __SIZE__, H = __SIZE__, cam = __CAMERA__, configs = __CONFIGS__;
__RENDERER_AND_CAMERA__
  var drawn = [], declared = [];
  for (var i = 0; i < configs.length; i++) {
    var loaded = await loadBoxmarch(THREE, GLTFLoader, 'model.glb', configs[i][1]);
    if (configs[i][2]) loaded.meshes[0].userData.boxmarchOccluders.minLayers = 0;
    var scene = new THREE.Scene();
    scene.add(loaded.scene);
    drawn.push({scene: scene, mesh: loaded.meshes[0]});
    declared.push(!!loaded.meshes[0].material.isRawShaderMaterial);
  }
  var pieces = [new THREE.Scene()];
  [THREE.FrontSide, THREE.DoubleSide].forEach(function (side) {
    var basic = new THREE.Mesh(drawn[0].mesh.geometry, new THREE.MeshBasicMaterial({color: 0xcccccc, side: side}));
    basic.matrixAutoUpdate = false;
    basic.matrix.copy(drawn[0].mesh.matrixWorld);
    pieces.push(new THREE.Scene().add(basic));
  });
  pieces.push(drawn[__FORCED__].mesh.userData.boxmarchOccluders.scene);  // its matrices and eye: set by each draw of the mesh
  __CLOCK_JS__
  var gl = renderer.getContext(), pixel = new Uint8Array(4);
  function frame(k) {
    var start = now();
    renderer.render(k < drawn.length ? drawn[k].scene : pieces[k - drawn.length], camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    return now() - start - overhead;
  }
  var images = [], best = [], prePass = [];
  for (var k = 0; k < drawn.length; k++) {
    frame(k);
    frame(k);  // r111 uploads an index buffer sorted in onBeforeRender at the next frame
    var px = new Uint8Array(W * H * 4);
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
    images.push(__b64(px));
    best.push(Infinity);
    var occluders = drawn[k].mesh.userData.boxmarchOccluders;
    prePass.push(occluders ? [occluders.drawn, occluders.layers] : [false, null]);
  }
  for (k = 0; k < pieces.length; k++) best.push(Infinity);
  for (var r = 0; r < __REPEATS__; r++) {
    for (k = 0; k < best.length; k++) best[k] = Math.min(best[k], frame(k));
  }
  var mesh = drawn[__FRONT_TO_BACK__].mesh, start = now();
  for (var s = 0; s < 20; s++) {
    mesh.userData.boxmarchBoxes.eye = null;  // as if the camera had moved
    sortBoxmarchFrontToBack(THREE, mesh, camera);
  }
  var sortMs = (now() - start - overhead) / 20;
  var extension = (gl.getSupportedExtensions() || []).indexOf('EXT_conservative_depth') >= 0;
  renderer.dispose();
  renderer.forceContextLoss();
  return {best: best.slice(0, drawn.length), pieces: best.slice(drawn.length), images: images, sort_ms: sortMs,
          boxes: mesh.userData.boxmarchBoxes.count, overhead: overhead,
          declared: declared, extension: extension, pre_pass: prePass};
}"""


def three_camera(to_view, eye):
    """The bench_gpu_cost camera in glTF's frame (Blender's x, z, -y); its up the view's own (a
    camera looking straight down has no up along Blender's z)."""
    from tests.engine_scene import TO_Y_UP

    forward, up = -np.asarray(to_view)[2, :3], np.asarray(to_view)[1, :3]
    return {"position": (TO_Y_UP @ eye[:3]).tolist(), "target": (TO_Y_UP @ (eye[:3] + forward)).tolist(),
            "up": (TO_Y_UP @ up).tolist(), "fov": 40.0, "near": 0.1, "far": 4000.0}


# A timing page's renderer (W x H, no antialiasing, cleared transparent) and its camera from
# three_camera's fields `cam`; the page declares W, H and cam before it.
RENDERER_AND_CAMERA_JS = """
  var renderer = new THREE.WebGLRenderer({canvas: document.createElement('canvas'), antialias: false, alpha: true});
  renderer.setPixelRatio(1);
  renderer.setSize(W, H, false);
  renderer.setClearColor(0x000000, 0);
  var camera = new THREE.PerspectiveCamera(cam.fov, W / H, cam.near, cam.far);
  camera.position.fromArray(cam.position);
  camera.up.fromArray(cam.up);
  camera.lookAt(new THREE.Vector3().fromArray(cam.target));"""


# Counts the SDF evaluations of loadBoxmarch's visibility and shade passes (useBoxmarchVisibility),
# as count_job counts the marching material's: each pass's march steps (plus the winner's 3 normal
# taps in the shade pass) summed by additive blending into its own float target, the depth tests
# as shipped (the visibility pass's count from a frame of its own; the shade pass's, its target
# made float, from a frame with the visibility pass as shipped).
PASSES_COUNT_AFTER = """var passes = null;
    scene.traverse(function (o) { if (o.userData.boxmarchVisibility) passes = o.userData.boxmarchVisibility; });
    if (!passes || !passes.supported) throw new Error('counting: no visibility passes ran');
    var gl = renderer.getContext();
    ['EXT_color_buffer_float', 'EXT_float_blend', 'OES_texture_float', 'WEBGL_color_buffer_float']
      .forEach(function (e) { gl.getExtension(e); });
    function counting(pass, lines) {
      var saved = pass.children.map(function (m) { return [m.material.fragmentShader, m.material.blending]; });
      pass.children.forEach(function (m) {
        var text = m.material.fragmentShader;
        lines.forEach(function (line) {
          if (text.indexOf(line[0]) < 0) throw new Error('counting: no ' + line[0]);
          text = text.replace(line[0], line[1]);
        });
        m.material.fragmentShader = text;
        m.material.blending = THREE.CustomBlending;
        m.material.blendEquation = THREE.AddEquation;
        m.material.blendSrc = THREE.OneFactor;
        m.material.blendDst = THREE.OneFactor;
        m.material.needsUpdate = true;
      });
      return function () {
        pass.children.forEach(function (m, i) {
          m.material.fragmentShader = saved[i][0];
          m.material.blending = saved[i][1];
          m.material.blendEquation = THREE.MinEquation;
          m.material.needsUpdate = true;
        });
      };
    }
    function read(target) {
      var values = new Float32Array(W * H * 4);
      renderer.readRenderTargetPixels(target, 0, 0, W, H, values);
      return values;
    }
    var miss = '  if (!hit) discard;';
    var restore = counting(passes.scenes.visibility, [[miss, '  gl_FragColor = vec4(float(steps));\\n  return;']]);
    renderer.render(scene, camera);
    var visibility = read(passes.targets.nearest);  // cleared to 1
    restore();
    passes.targets.shaded.dispose();
    passes.targets.shaded.texture.type = THREE.FloatType;
    counting(passes.scenes.shade, [[miss, '  if (!hit) { gl_FragColor = vec4(float(steps)); return; }'],
      ['  if (depth != resolved) discard;', '  gl_FragColor = vec4(float(steps + (depth == resolved ? normalTaps : 0)));\\n  return;']]);
    renderer.render(scene, camera);
    var shade = read(passes.targets.shaded), counts = new Float32Array(W * H * 4);
    for (var i = 0; i < W * H; i++) counts[4 * i] = visibility[4 * i] - 1 + shade[4 * i];
    return {counts: __f64(counts)};"""


def loader_options(sdf, config):
    """loadBoxmarch's options for ``config`` on a scene of shape ``sdf``: the row's, and the scene's map."""
    options = dict(config[1])
    if options.pop("marched", False):
        options["map"], options["occluders"] = MARCHED[sdf]
    elif MAPS[sdf] is not None:
        options["map"] = MAPS[sdf]
    return options


def counting_setup(sdf, config):
    """count_job's setup: the export loaded as TIMING_JOB loads it for ``config``."""
    force = " loaded.meshes[0].userData.boxmarchOccluders.minLayers = 0;" if config[2] else ""
    return (f"scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'model.glb', "
            f"{json.dumps(loader_options(sdf, config), allow_nan=False)});{force} scene.add(loaded.scene);")


def exported_glb(bpy, name, scene, folder):
    from bench.bench_preview_cost import baked_object
    from boxmarch.export import scene as export_scene

    ob = baked_object(bpy, name, scene)
    path = os.path.join(folder, "model.glb")
    export_scene.export_objects(bpy.context, [ob], "GLTF", path, "NORMAL_FRAME")
    bpy.data.objects.remove(ob)
    return Path(path).read_bytes(), Path(path).with_suffix(".boxmarch.json").read_bytes()


def rows_for(name, scene, glb, sidecar, release):
    import base64

    from tests.engines import threejs

    _origins, _rotations, _half, sdf, (_to_clip, to_view, eye) = scene
    # before r163 declareDepth changes nothing: the ShaderMaterial rows would repeat the others
    configs = [c for c in CONFIGS if c[1].get("declareDepth", True) or int(threejs.RELEASES[release].revision) >= 163]
    loaded = [[label, loader_options(sdf, (label, options, force)), force] for label, options, force in configs]
    parts = {"__SIZE__": str(SIZE), "__CAMERA__": json.dumps(three_camera(to_view, eye), allow_nan=False),
             "__CONFIGS__": json.dumps(loaded, allow_nan=False),
             "__REPEATS__": str(REPEATS), "__FRONT_TO_BACK__": str(FRONT_TO_BACK), "__FORCED__": str(FORCED),
             "__CLOCK_JS__": threejs.CLOCK_JS, "__RENDERER_AND_CAMERA__": RENDERER_AND_CAMERA_JS}
    js = TIMING_JOB
    for key, value in parts.items():
        js = js.replace(key, value)
    out = threejs.run_jobs(glb, [js], threejs.shipped_material(release), release,
                           {"model.boxmarch.json": sidecar})[0]
    # one page per count: a page of them all outlasts the harness's time limit on the pile
    counted = [threejs.run_jobs(glb, [threejs.count_job(counting_setup(sdf, config), SIZE, SIZE, three_camera(to_view, eye),
                                                        *([PASSES_COUNT_AFTER] if config[1].get("visibilityPass") else []))],
                                threejs.shipped_material(release), release, {"model.boxmarch.json": sidecar})[0]
               for config in configs]
    images = [np.frombuffer(base64.b64decode(b), np.uint8).reshape(SIZE, SIZE, 4).astype(int) for b in out["images"]]
    rows = []
    for (label, *_), declared, best, image, (shot, evaluations), (ran, layers) in zip(
            configs, out["declared"], out["best"], images, counted, out["pre_pass"]):
        covered = (images[0][..., 3] > 0) | (image[..., 3] > 0)
        changed = (np.abs(image - images[0])[..., :3].max(-1) > 1) & covered
        depth = "depth_greater" if declared and out["extension"] else "none"
        per_pixel = evaluations.sum() / max((shot.pixels[..., 3] > 0).sum(), 1)
        ran = f"{'yes' if ran else 'no'} ({layers:.1f} layers)" if layers is not None else "no"
        rows.append([name, f"r{threejs.RELEASES[release].revision}", label, depth, ran, f"{per_pixel:.1f}", f"{best:.1f}",
                     f"{out['best'][0] / best:.2f}x", f"{100 * changed.sum() / max(covered.sum(), 1):.2f}%",
                     f"{100 * covered.mean():.0f}%", f"{out['sort_ms']:.1f} ({out['boxes']} boxes)",
                     f"{out['overhead']:.1f}"])
    pieces = [[name, f"r{threejs.RELEASES[release].revision}", label, f"{ms:.1f}"] for label, ms in zip(PIECES, out["pieces"])]
    return rows, pieces


def main():
    names = sys.argv[1:] or SCENES
    unknown = [name for name in names if name not in SCENES]
    if unknown:
        sys.exit(f"bench_threejs_cost: no scene {unknown[0]!r} (its scenes: {', '.join(SCENES)})")
    import bpy
    from tests.engines import threejs

    import boxmarch
    from bench.bench_gpu_cost import pile_of_boxes, scenes_to_measure
    from bench.common import table

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    threejs.TIMEOUT_S = 1800  # a page times every configuration of a 4,000-link pile: minutes on SwiftShader, more on a busy machine
    made = scenes_to_measure(SIZE, 8)
    made["pile of boxes"] = pile_of_boxes(SIZE, SIZE)
    releases = [r for r in ("r180", "r111") if threejs.available(r) is None]
    rows, pieces = [], []
    with tempfile.TemporaryDirectory(prefix="bench-threejs-") as folder:
        for name in names:
            glb, sidecar = exported_glb(bpy, name, made[name], folder)
            for release in releases:
                configurations, parts = rows_for(name, made[name], glb, sidecar, release)
                rows += configurations
                pieces += parts
                print(table(HEADERS, configurations), flush=True)  # each scene's rows as they come
    print(f"three.js on SwiftShader (headless Chromium), {SIZE} x {SIZE} px, best of {REPEATS}; "
          "the material's defaults (maxSteps 96, epsilon 1e-4) in every row")
    print(table(HEADERS, rows))
    print("\nPieces of a frame, timed in the same round robin (PIECES)")
    print(table(["scene", "three.js", "what is drawn", "frame ms"], pieces))


if __name__ == "__main__":
    main()

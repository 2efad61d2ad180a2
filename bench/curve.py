"""Run time against error: the same links drawn as boxmarch boxes and as triangle meshes, each
picture compared with one exact reference at the same pixel centres.

Scenes (curve_scenes): *close chain*, the demo character's chains (addon/boxmarch/demo_character.py,
posed as its POSE says, tests/test_demo.py's forward kinematics) seen close, links 100-400 px
long; *10,000-link chain*, bench_boxes_vs_triangles.chain_rows at 1920 x 1080 (links about 15 px);
*pile*, bench_gpu_cost.pile_of_links, 4,000 links heaped in a 4 x 4 x 4 cube seen through it.
Every shape is the LINK preset (sdf.glsl sdf_preset_link, a torus stretched along its long axis).

The reference (exact_picture) is computed here in float64 with NumPy, independent of both the
shaders and the C++ core: one ray from the eye through each pixel centre, tested against every
box whose projected bounds hold the pixel; inside the box the exact SDF of the link (sd_link is
exact, bench_boxes_vs_triangles.link_distance) is sphere-traced from the box's entry until it is
under TOLERANCE units (REFERENCE_STEPS at most; a ray still farther than TOLERANCE after them
counts as a miss); the nearest hit over the boxes wins.
Its depth (along the view axis) and normal (the SDF's gradient by central differences of
1e-7 units) are the hit's.

The error of a picture (picture_error), against the reference: *coverage*, pixels covered in
one picture only, as a share of the pixels the reference covers; where both cover, *depth*, the
99th percentile of |depth - reference| in pixel widths at that depth, and *normal*, the 99th
percentile of the angle between the normals, in degrees.

Methods, drawn side by side in one process per renderer: the boxes (baked in bpy, sorted axes)
at the renderer's shipped defaults and at other march settings (BOX_SETTINGS); triangle meshes of
the same links at MESH_LEVELS tessellations (bench_boxes_vs_triangles.link_mesh: n vertices
round the tube at each of 2m + 2 rings along the path, vertices and normals on the true
surface), from (3, 2) (36 triangles, a link that still reads as a link, with its hole) to film
quality, each level drawn while the scene's triangles stay under the budget.

Renderers: *llvmpipe*, the Blender preview's own draw (preview.draw.draw_object, bpy's gpu module
on Mesa llvmpipe) against the mesh drawn by one indexed draw with back faces culled and a Lambert
fragment stage; *SwiftShader*, three.js r111 in headless Chromium (tests/engines/threejs.py):
the export loaded by loadBoxmarch against the mesh as a BufferGeometry with MeshNormalMaterial.
Frame: clear, draw, a 1-pixel read-back (which waits for the frame); every configuration in round
robin, REPEATS frames each, the median. This machine's 2 cores are shared with other jobs: only
frames timed in the same round robin are compared with each other. SwiftShader pictures give the
coverage only (alpha); depth and normal errors come from llvmpipe, where the boxes draw their
NORMAL output and both methods' depth buffers are read.

    PYTHONPATH=addon python3 -m bench.curve [--quick] [--json out.json] [--before before.json]
    PYTHONPATH=addon python3 -m bench.curve --from-json out.json [--before before.json]  # no measuring

writes docs/curve_llvmpipe.png and docs/curve_swiftshader.png (--before: a previous run's points
drawn hollow beside this run's, and its boxes' rows beside this run's in a table) and prints the
tables of docs/BENCHMARKS.md.
"""
import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from bench.bench_boxes_vs_triangles import chain_mesh, link_distance
from bench.bench_threejs_cost import MARCHED

HERE = Path(__file__).resolve().parent
TOLERANCE = 1e-10      # the reference's hit distance, scene units
# The reference's sphere-tracing steps per ray and box. A ray entering a round end at a grazing
# angle closes in on the surface slowly: at 400 steps 142 pixels of the 10,000-link chain, 110 of
# the close chain and 35 of the pile that cross the surface (up to half a pixel deep) were still
# undecided and counted as misses. 40,000 steps draw the chains' pictures 4,000 do; the pile's
# reference takes 4 s more than at 400 (only those few rays take the steps).
REFERENCE_STEPS = 4000
PAIRS_PER_CHUNK = 1_500_000
REPEATS = 5
# (n, m): n sides round the tube, m segments per half circle of the path (2 n (2 m + 2) triangles)
MESH_LEVELS = ((3, 2), (4, 2), (6, 3), (8, 4), (12, 6), (16, 8), (24, 12), (32, 16), (48, 24), (64, 32), (96, 48),
               (128, 64))
TRIANGLE_BUDGET = 4_000_000   # a scene's mesh levels stop at the first over it (the run's time: docs/BENCHMARKS.md)
LINK_MAP = "return sdf_preset_link(p, box_half);"
# label, the preview's settings (max_steps, epsilon, quality), loadBoxmarch's options
BOX_SETTINGS = {
    "llvmpipe": (("defaults (64 steps, epsilon 1e-3)", (64, 1e-3, 1.0)),
                 ("32 steps, 1e-3", (32, 1e-3, 1.0)),
                 ("quality 0.5", (64, 1e-3, 0.5)),
                 ("96 steps, 1e-4", (96, 1e-4, 1.0)),
                 ("512 steps, 1e-6", (512, 1e-6, 1.0))),
    "SwiftShader": (("defaults (96 steps, epsilon 1e-4)", {}),
                    ("64 steps, 1e-3", {"maxSteps": 64, "epsilon": 1e-3}),
                    ("quality 0.5", {"quality": 0.5}),
                    ("512 steps, 1e-6", {"maxSteps": 512, "epsilon": 1e-6}),
                    # the preset's hit is solved in closed form at every setting above; the map
                    # written as a user's own is marched: the issue's bar, in the same page
                    ("512 steps, 1e-6, marched (the map as a user's own)",
                     {"map": MARCHED["LINK"][0], "occluders": MARCHED["LINK"][1], "maxSteps": 512, "epsilon": 1e-6})),
}


class CurveScene(NamedTuple):
    """Links (every one the LINK preset; half-extents longest axis first) and the camera."""

    origins: np.ndarray    # (K, 3)
    rotations: np.ndarray  # (K, 3, 3), columns the box's local axes
    half: np.ndarray       # (K, 3)
    camera: tuple          # bench_gpu_cost.camera's (object_to_clip, object_to_view, eye4)
    width: int
    height: int

    def as_bench_scene(self):
        """The (origins, rotations, half, sdf, camera) tuple of the other benches."""
        return self.origins, self.rotations, self.half, "LINK", self.camera


class Picture(NamedTuple):
    """One picture at pixel centres, row 0 at the top."""

    covered: np.ndarray         # (H, W) bool
    depth: np.ndarray = None    # (H, W) view-axis distance where covered
    normal: np.ndarray = None   # (H, W, 3) unit object-space normal where covered
    focal: float = None         # the reference's: pixel widths per unit of lateral size at unit depth


def box_corners(scene):
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float64)
    return scene.origins[:, None, :] + np.einsum("kij,kvj->kvi", scene.rotations, signs[None] * scene.half[:, None, :])


def in_view(origins, rotations, half, camera, width, height):
    """Which boxes lie wholly in front of the camera and at least partly in its picture."""
    scene = CurveScene(origins, rotations, half, camera, width, height)
    corners = box_corners(scene)
    clip = corners @ camera[0][:3, :3].T + camera[0][:3, 3]
    w = corners @ camera[0][3, :3] + camera[0][3, 3]
    front = (w > 0.1).all(1)
    ndc = clip[..., :2] / np.where(front[:, None], w, 1.0)[..., None]
    return front & (ndc.min(1) < 1).all(1) & (ndc.max(1) > -1).all(1)


def close_chain(width, height):
    """The demo character's posed chains, the links in view of a camera 1.6 units off the
    necklace and sash on its chest."""
    from bench.bench_gpu_cost import camera
    from tests.test_demo import posed_links

    centres, rotations, sizes = posed_links()
    view = camera((0.55, -2.1, 6.55), (0.05, -0.3, 6.1), width, height)
    keep = in_view(centres, rotations, sizes / 2, view, width, height)
    return CurveScene(centres[keep], rotations[keep], sizes[keep] / 2, view, width, height)


def long_chain(count, width, height):
    from bench.bench_boxes_vs_triangles import chain_rows

    origins, rotations, half, _sdf, view = chain_rows(count, (width, height))
    return CurveScene(origins, rotations, half, view, width, height)


def pile(count, width, height):
    from bench.bench_gpu_cost import pile_of_links

    origins, rotations, half, _sdf, view = pile_of_links(count, np.random.default_rng(1), width, height)
    return CurveScene(origins, rotations, half, view, width, height)


def curve_scenes(quick=False):
    """name -> CurveScene of the curve (quick: smaller pictures, fewer links)."""
    if quick:
        return {"close chain": close_chain(480, 270), "1,000-link chain": long_chain(1000, 960, 540),
                "pile": pile(500, 480, 270)}
    return {"close chain": close_chain(960, 540), "10,000-link chain": long_chain(10_000, 1920, 1080),
            "pile": pile(4000, 960, 540)}


def pixel_rays(scene):
    """(eye (3,), unit directions (H, W, 3)) through the pixel centres, row 0 at the top."""
    to_clip, _to_view, eye = scene.camera
    x = (np.arange(scene.width) + 0.5) / scene.width * 2 - 1
    y = 1 - (np.arange(scene.height) + 0.5) / scene.height * 2
    ndc = np.stack(np.broadcast_arrays(x[None, :], y[:, None], 1.0, 1.0), -1)
    far = ndc @ np.linalg.inv(to_clip).T
    far = far[..., :3] / far[..., 3:]
    directions = far - eye[:3]
    return np.asarray(eye[:3], np.float64), directions / np.linalg.norm(directions, axis=-1, keepdims=True)


def box_pixel_pairs(scene):
    """(box, pixel) index pairs of every pixel centre inside each box's projected bounds."""
    to_clip = scene.camera[0]
    corners = box_corners(scene)
    clip = corners @ to_clip[:3, :3].T + to_clip[:3, 3]
    w = corners @ to_clip[3, :3] + to_clip[3, 3]
    if (w <= 0).any():
        raise ValueError("curve: a box reaches behind the camera")
    column = (clip[..., 0] / w + 1) / 2 * scene.width - 0.5
    row = (1 - clip[..., 1] / w) / 2 * scene.height - 0.5
    c0 = np.clip(np.ceil(column.min(1)), 0, scene.width).astype(np.int64)
    c1 = np.clip(np.floor(column.max(1)), -1, scene.width - 1).astype(np.int64)
    r0 = np.clip(np.ceil(row.min(1)), 0, scene.height).astype(np.int64)
    r1 = np.clip(np.floor(row.max(1)), -1, scene.height - 1).astype(np.int64)
    cols, rows = np.maximum(c1 - c0 + 1, 0), np.maximum(r1 - r0 + 1, 0)
    counts = cols * rows
    boxes = np.repeat(np.arange(len(counts)), counts)
    k = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    pixel = (r0[boxes] + k // cols[boxes]) * scene.width + c0[boxes] + k % cols[boxes]
    return boxes, pixel


def _trace(origins_local, directions_local, half, t, t_exit):
    """Sphere tracing of sd_link along each ray from t to t_exit: (hit, t)."""
    hit = np.zeros(len(t), bool)
    active = np.arange(len(t))
    for _ in range(REFERENCE_STEPS):
        if not len(active):
            break
        distance = link_distance(origins_local[active] + t[active, None] * directions_local[active], half[active])
        done = distance < TOLERANCE
        hit[active[done]] = True
        t[active] += np.where(done, 0.0, distance)
        active = active[~done & (t[active] <= t_exit[active])]
    return hit, t


def exact_picture(scene):
    """The float64 reference Picture of ``scene`` (see the module's docstring)."""
    if (np.diff(scene.half, axis=1) > 0).any():
        raise ValueError("curve: half-extents must be sorted longest first (the bake's sorted axes)")
    eye, directions = pixel_rays(scene)
    directions = directions.reshape(-1, 3)
    boxes, pixels = box_pixel_pairs(scene)
    pixel_count = scene.width * scene.height
    nearest = np.full(pixel_count, np.inf)
    normal = np.zeros((pixel_count, 3))
    for start in range(0, len(boxes), PAIRS_PER_CHUNK):
        box, pixel = boxes[start:start + PAIRS_PER_CHUNK], pixels[start:start + PAIRS_PER_CHUNK]
        turn = scene.rotations[box]
        o = np.einsum("kji,kj->ki", turn, eye - scene.origins[box])
        d = np.einsum("kji,kj->ki", turn, directions[pixel])
        half = scene.half[box]
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse = 1.0 / d
            near_side, far_side = (-half - o) * inverse, (half - o) * inverse
        t0 = np.nan_to_num(np.minimum(near_side, far_side), nan=-np.inf).max(1)
        t1 = np.nan_to_num(np.maximum(near_side, far_side), nan=np.inf).min(1)
        crosses = t1 > np.maximum(t0, 0.0)
        box, pixel, o, d, half, turn = box[crosses], pixel[crosses], o[crosses], d[crosses], half[crosses], turn[crosses]
        hit, t = _trace(o, d, half, np.maximum(t0[crosses], 0.0), t1[crosses])
        box, pixel, o, d, half, turn, t = (a[hit] for a in (box, pixel, o, d, half, turn, t))
        order = np.lexsort((t, pixel))
        first = np.ones(len(order), bool)
        first[1:] = pixel[order][1:] != pixel[order][:-1]
        chosen = order[first]
        better = t[chosen] < nearest[pixel[chosen]]
        chosen = chosen[better]
        p = o[chosen] + t[chosen, None] * d[chosen]
        step = 1e-7
        gradient = np.stack([link_distance(p + step * e, half[chosen]) - link_distance(p - step * e, half[chosen])
                             for e in np.eye(3)], -1)
        gradient /= np.linalg.norm(gradient, axis=1, keepdims=True)
        nearest[pixel[chosen]] = t[chosen]
        normal[pixel[chosen]] = np.einsum("kij,kj->ki", turn[chosen], gradient)
    covered = np.isfinite(nearest)
    to_view = scene.camera[1]
    depth = np.where(covered, np.inf, np.nan)
    hit_points = eye + np.where(covered, nearest, 0.0)[:, None] * directions
    depth[covered] = -(hit_points[covered] @ to_view[2, :3] + to_view[2, 3])
    shape = (scene.height, scene.width)
    focal = scene.height / 2 * np.linalg.norm(scene.camera[0][1, :3])  # projection[1][1] = 1 / tan(fov / 2)
    return Picture(covered.reshape(shape), depth.reshape(shape), normal.reshape(shape + (3,)), focal)


def picture_error(reference, picture):
    """{'coverage': % of the reference's covered pixels covered in one picture only, 'depth': 99th
    percentile of the depth error in pixel widths, 'normal': 99th percentile of the normal's angle
    in degrees} (depth and normal where both cover and the picture has them, else None)."""
    covered = max(int(reference.covered.sum()), 1)
    error = {"coverage": 100.0 * int((reference.covered ^ picture.covered).sum()) / covered,
             "depth": None, "normal": None}
    both = reference.covered & picture.covered
    if not both.any():
        return error
    if picture.depth is not None:
        pixel_width = reference.depth[both] / reference.focal
        error["depth"] = float(np.percentile(np.abs(picture.depth[both] - reference.depth[both]) / pixel_width, 99))
    if picture.normal is not None:
        n = picture.normal[both] / np.linalg.norm(picture.normal[both], axis=1, keepdims=True)
        cosine = np.clip(np.einsum("ij,ij->i", n, reference.normal[both]), -1.0, 1.0)
        error["normal"] = float(np.percentile(np.degrees(np.arccos(cosine)), 99))
    return error



def mesh_levels(scene, budget=TRIANGLE_BUDGET):
    """The MESH_LEVELS whose triangles for the scene's links stay within ``budget``."""
    return [(n, m) for n, m in MESH_LEVELS if 2 * n * (2 * m + 2) * len(scene.origins) <= budget]


def box_bytes(layout="CLASSIC"):
    """Vertex + index bytes of one box as the preview draws it: 8 vertices of the layout, 36 indices."""
    from bench.bench_boxes_vs_triangles import layout_bytes

    return 8 * layout_bytes()[layout] + 36 * 4


def mesh_bytes(vertices, triangles):
    """float32 position and normal a vertex, 4-byte indices."""
    return 24 * vertices + 12 * triangles


def _median_ms(samples):
    return 1e3 * float(np.median(samples))


def llvmpipe_points(bpy, name, scene, reference, levels):
    """The scene's points on llvmpipe (see the module's docstring): one dict per configuration."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    from bench.bench_boxes_vs_triangles import NORMAL_FRAGMENT, triangle_shader
    from bench.bench_gpu_frame import view_distance
    from bench.bench_preview_cost import baked_object
    from bench.common import offscreen_frame
    from boxmarch.preview import draw

    to_clip, to_view, _eye = scene.camera
    projection = to_clip @ np.linalg.inv(to_view)
    ob = baked_object(bpy, name, scene.as_bench_scene())
    offscreen = gpu.types.GPUOffScreen(scene.width, scene.height, format="RGBA32F")
    shaders = (triangle_shader(), triangle_shader(NORMAL_FRAGMENT))
    configs = [{"method": "boxes", "setting": label, "values": values, "triangles": 12 * len(scene.origins),
                "bytes": box_bytes() * len(scene.origins)} for label, values in BOX_SETTINGS["llvmpipe"]]
    for n, m in levels:
        positions, normals, triangles = chain_mesh(scene.as_bench_scene(), n, m)
        configs.append({"method": "mesh", "setting": f"{n} x {2 * m + 2}", "triangles": len(triangles),
                        "bytes": mesh_bytes(len(positions), len(triangles)), "draw calls": 1,
                        "batch": batch_for_shader(shaders[0], "TRIS", {"pos": positions, "nor": normals},
                                                  indices=triangles)})

    def draw_config(config, output):
        if config["method"] == "boxes":
            ob.boxmarch.max_steps, ob.boxmarch.epsilon, ob.boxmarch.quality = config["values"]
            draw.draw_object(ob, to_view, projection, True, output)
            return
        shader = shaders[output]
        gpu.state.face_culling_set("BACK")
        shader.bind()
        shader.uniform_float("to_clip", to_clip.T.ravel().tolist())
        shader.uniform_float("to_view", (np.eye(4) if output else to_view).T.ravel().tolist())
        config["batch"].draw(shader)
        gpu.state.face_culling_set("NONE")

    for config in configs:
        image, depth = offscreen_frame(offscreen, lambda: draw_config(config, 1), read=True, depth=True)
        image, depth = image[::-1], depth[::-1].astype(np.float64)
        covered = image[..., 3] > 0
        picture = Picture(covered, np.where(covered, view_distance(depth, to_clip, to_view), np.nan),
                          image[..., :3].astype(np.float64) * 2 - 1)
        config.update(picture_error(reference, picture))
        config["times"], config["cpu"] = [], []
    for _ in range(REPEATS):
        for config in configs:
            start, cpu = time.perf_counter(), time.process_time()
            offscreen_frame(offscreen, lambda: draw_config(config, 0))
            config["times"].append(time.perf_counter() - start)
            config["cpu"].append(time.process_time() - cpu)
    offscreen.free()
    bpy.data.objects.remove(ob)
    return [{"renderer": "llvmpipe", "scene": name, "ms": _median_ms(c.pop("times")), "cpu ms": _median_ms(c.pop("cpu")),
             **{k: v for k, v in c.items() if k not in ("batch", "values")}} for c in configs]


# One page per scene: the boxes loaded once per setting and each mesh level, each drawn once for
# its picture (coverage as bits, row 0 at the bottom) and its draw calls, then timed in round robin.
THREEJS_JOB = """async function (gltf) {
  var W = __W__, H = __H__, cam = __CAMERA__, settings = __SETTINGS__, meshes = __MESHES__;
__RENDERER_AND_CAMERA__
  var scenes = [];
  for (var i = 0; i < settings.length; i++) {
    var loaded = await loadBoxmarch(THREE, GLTFLoader, 'model.glb', settings[i]);
    scenes.push(new THREE.Scene().add(loaded.scene));
  }
  var material = new THREE.MeshNormalMaterial();
  for (i = 0; i < meshes.length; i++) {
    var bytes = await (await fetch(meshes[i].file)).arrayBuffer(), v = meshes[i].vertices;
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(bytes, 0, 3 * v), 3));
    geometry.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(bytes, 12 * v, 3 * v), 3));
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(bytes, 24 * v, 3 * meshes[i].triangles), 1));
    scenes.push(new THREE.Scene().add(new THREE.Mesh(geometry, material)));
  }
  __CLOCK_JS__
  var gl = renderer.getContext(), pixel = new Uint8Array(4);
  function frame(k) {
    var start = now();
    renderer.render(scenes[k], camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    return now() - start - overhead;
  }
  var pictures = [], calls = [], times = [];
  for (var k = 0; k < scenes.length; k++) {
    frame(k);  // the warm-up (no row sorts its boxes: one frame draws what the timed ones draw)
    calls.push(renderer.info.render.calls);
    var px = new Uint8Array(W * H * 4), bits = new Uint8Array(Math.ceil(W * H / 8));
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
    for (var p = 0; p < W * H; p++) if (px[4 * p + 3] > 0) bits[p >> 3] |= 1 << (p & 7);
    pictures.push(__b64(bits));
    times.push([]);
  }
  for (var r = 0; r < __REPEATS__; r++) {
    for (k = 0; k < scenes.length; k++) times[k].push(frame(k));
  }
  renderer.dispose();
  renderer.forceContextLoss();
  return {pictures: pictures, calls: calls, times: times};
}"""


def swiftshader_points(bpy, name, scene, reference, levels, folder):
    """The scene's points on SwiftShader (three.js r111): one dict per configuration."""
    import base64

    from bench.bench_threejs_cost import RENDERER_AND_CAMERA_JS, exported_glb, three_camera
    from tests.engine_scene import TO_Y_UP
    from tests.engines import threejs

    glb, sidecar = exported_glb(bpy, name, scene.as_bench_scene(), folder)
    settings = BOX_SETTINGS["SwiftShader"]
    configs = [{"method": "boxes", "setting": label, "triangles": 12 * len(scene.origins), "bytes": len(glb)}
               for label, _options in settings]
    files, meshes = {"model.boxmarch.json": sidecar}, []
    for level, (n, m) in enumerate(levels):
        positions, normals, triangles = chain_mesh(scene.as_bench_scene(), n, m)
        files[f"mesh{level}.bin"] = ((positions @ TO_Y_UP.T.astype(np.float32)).tobytes()
                                     + (normals @ TO_Y_UP.T.astype(np.float32)).tobytes() + triangles.tobytes())
        meshes.append({"file": f"mesh{level}.bin", "vertices": len(positions), "triangles": len(triangles)})
        configs.append({"method": "mesh", "setting": f"{n} x {2 * m + 2}", "triangles": len(triangles),
                        "bytes": mesh_bytes(len(positions), len(triangles))})
    parts = {"__W__": str(scene.width), "__H__": str(scene.height), "__REPEATS__": str(REPEATS),
             "__CAMERA__": json.dumps(three_camera(scene.camera[1], scene.camera[2]), allow_nan=False),
             "__SETTINGS__": json.dumps([{"map": LINK_MAP, **options} for _label, options in settings], allow_nan=False),
             "__MESHES__": json.dumps(meshes, allow_nan=False), "__CLOCK_JS__": threejs.CLOCK_JS,
             "__RENDERER_AND_CAMERA__": RENDERER_AND_CAMERA_JS}
    js = THREEJS_JOB
    for key, value in parts.items():
        js = js.replace(key, value)
    out = threejs.run_jobs(glb, [js], threejs.shipped_material("r111"), "r111", files, timeout_s=1800)[0]
    points = []
    for config, bits, calls, times in zip(configs, out["pictures"], out["calls"], out["times"]):
        unpacked = np.unpackbits(np.frombuffer(base64.b64decode(bits), np.uint8), bitorder="little")
        covered = unpacked[:scene.width * scene.height].reshape(scene.height, scene.width)[::-1].astype(bool)
        points.append({"renderer": "SwiftShader", "scene": name, "ms": float(np.median(times)), **config,
                       "draw calls": calls, **picture_error(reference, Picture(covered))})
    return points


def crossing(points, renderer, scene):
    """(the boxes at the renderer's defaults, the mesh of fewest triangles whose coverage error is
    at most theirs or None, the mesh of most triangles at most the boxes' frame time or None)."""
    here = [p for p in points if p["renderer"] == renderer and p["scene"] == scene]
    boxes = next(p for p in here if p["method"] == "boxes" and p["setting"].startswith("defaults"))
    meshes = sorted((p for p in here if p["method"] == "mesh"), key=lambda p: p["triangles"])
    equal = next((p for p in meshes if p["coverage"] <= boxes["coverage"]), None)
    as_fast = [p for p in meshes if p["ms"] <= boxes["ms"]]
    return boxes, equal, as_fast[-1] if as_fast else None


def crossing_lines(points):
    lines = []
    for renderer, scene in dict.fromkeys((p["renderer"], p["scene"]) for p in points):
        boxes, equal, as_fast = crossing(points, renderer, scene)
        largest = max((p for p in points if p["renderer"] == renderer and p["scene"] == scene and p["method"] == "mesh"),
                      key=lambda p: p["triangles"])
        line = (f"{renderer}, {scene}: boxes (defaults) {boxes['coverage']:.3f} % coverage error, {boxes['ms']:.1f} ms; ")
        if equal:
            cpu = (f", CPU {equal['cpu ms'] / boxes['cpu ms']:.2f}x" if equal.get("cpu ms") and boxes.get("cpu ms") else "")
            line += (f"the mesh matches it from {equal['triangles']:,} triangles ({equal['setting']}, "
                     f"{equal['coverage']:.3f} %), {equal['ms']:.1f} ms = {equal['ms'] / boxes['ms']:.2f}x the boxes' time{cpu}; ")
        else:
            line += (f"no mesh up to {largest['triangles']:,} triangles reaches it ({largest['coverage']:.3f} % "
                     f"at {largest['ms'] / boxes['ms']:.2f}x the boxes' time); ")
        if as_fast:
            line += (f"the mesh as fast as the boxes ({as_fast['triangles']:,} triangles) has "
                     f"{as_fast['coverage'] / max(boxes['coverage'], 1e-9):.1f}x their error")
        else:
            line += "every mesh is slower than the boxes"
        lines.append(line)
    return lines


HEADERS = ["renderer", "scene", "method", "setting", "triangles", "bytes", "draw calls", "coverage error %",
           "depth p99 (px)", "normal p99 (deg)", "frame ms (median)", "CPU ms (median)"]


def table_rows(points):
    number = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
    return [[p["renderer"], p["scene"], p["method"], p["setting"], f"{p['triangles']:,}", f"{p['bytes']:,}",
             str(p.get("draw calls", "-")), f"{p['coverage']:.3f}", number(p["depth"], ".2f"),
             number(p["normal"], ".2f"), f"{p['ms']:.1f}", number(p.get("cpu ms"), ".1f")] for p in points]


def plot(points, renderer, path, before=()):
    """Frame time against coverage error, one panel per scene: the boxes' settings as points, the
    meshes as a line through their levels; ``before``: a previous run's points drawn hollow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(p["scene"] for p in points if p["renderer"] == renderer))
    figure, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.6), squeeze=False)
    for axis, scene in zip(axes[0], scenes):
        for run, hollow in ((before, True), (points, False)):
            here = [p for p in run if p["renderer"] == renderer and p["scene"] == scene]
            if not here:
                continue
            meshes = sorted((p for p in here if p["method"] == "mesh"), key=lambda p: p["triangles"])
            boxes = [p for p in here if p["method"] == "boxes"]
            style = {"markerfacecolor": "none"} if hollow else {}
            tag = " (before)" if hollow else ""
            axis.plot([p["coverage"] for p in meshes], [p["ms"] for p in meshes], "o-", color="tab:blue",
                      alpha=0.5 if hollow else 1.0, label="triangle mesh" + tag, **style)
            for p in meshes if not hollow else ():
                axis.annotate(f"{p['triangles'] / 1e3:,.0f}k", (p["coverage"], p["ms"]), fontsize=7,
                              xytext=(3, 3), textcoords="offset points")
            axis.plot([p["coverage"] for p in boxes], [p["ms"] for p in boxes], "s", color="tab:red",
                      alpha=0.5 if hollow else 1.0, label="boxes" + tag, **style)
            for p in boxes if not hollow else ():
                axis.annotate(p["setting"].split(" (")[0], (p["coverage"], p["ms"]), fontsize=7, color="tab:red",
                              xytext=(3, -9), textcoords="offset points")
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel("coverage error (% of the reference's covered pixels)")
        axis.set_ylabel("frame ms (median)")
        axis.set_title(f"{scene} ({renderer})", fontsize=10)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    written = path.with_suffix(".tmp.png")
    figure.savefig(written, dpi=90)
    plt.close(figure)
    os.replace(written, path)


def write_json(path, points):
    written = Path(str(path) + ".tmp")
    written.write_text(json.dumps(points, indent=1, allow_nan=False))
    os.replace(written, path)


BEFORE_HEADERS = ["renderer", "scene", "boxes' setting", "coverage error % (before / after)",
                  "depth p99 px (before / after)", "normal p99 deg (before / after)", "frame ms (before / after)",
                  "CPU ms (before / after)"]


def before_after_rows(before, points):
    """The boxes' rows of two runs side by side (a previous run, ``before``, and this one)."""
    number = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
    earlier = {(p["renderer"], p["scene"], p["setting"]): p for p in before if p["method"] == "boxes"}
    rows = []
    for p in points:
        b = earlier.get((p["renderer"], p["scene"], p["setting"]))
        if p["method"] != "boxes" or b is None:
            continue
        rows.append([p["renderer"], p["scene"], p["setting"], f"{b['coverage']:.3f} / {p['coverage']:.3f}",
                     f"{number(b['depth'], '.2f')} / {number(p['depth'], '.2f')}",
                     f"{number(b['normal'], '.2f')} / {number(p['normal'], '.2f')}",
                     f"{b['ms']:.1f} / {p['ms']:.1f} ({b['ms'] / p['ms']:.2f}x)",
                     f"{b['cpu ms']:.1f} / {p['cpu ms']:.1f} ({b['cpu ms'] / p['cpu ms']:.2f}x)"
                     if b.get("cpu ms") and p.get("cpu ms") else "-"])
    return rows


def report(points, before, plots, renderers):
    """Prints the tables and crossing points of ``points`` and writes the plots into ``plots``."""
    from bench.common import table

    print(table(HEADERS, table_rows(points)))
    print("\n" + "\n".join(crossing_lines(points)))
    if before:
        print("\nThe boxes before (--before) and now")
        print(table(BEFORE_HEADERS, before_after_rows(before, points)))
    if plots:
        for renderer in renderers:
            plot(points, renderer, Path(plots) / f"curve_{renderer.lower()}.png", before)


RENDERERS = ("llvmpipe", "SwiftShader")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller pictures and scenes (about a minute)")
    parser.add_argument("--renderers", nargs="*", default=list(RENDERERS), choices=RENDERERS)
    parser.add_argument("--json", help="write the points here")
    parser.add_argument("--before", help="a previous run's --json, drawn hollow in the plots")
    parser.add_argument("--plots", default=None, help="folder of curve_*.png (default: docs/; none with --quick)")
    parser.add_argument("--from-json", help="measure nothing: report this earlier run's --json")
    args = parser.parse_args()
    before = json.loads(Path(args.before).read_text()) if args.before else ()
    plots = args.plots or (None if args.quick else str(HERE.parent / "docs"))
    if args.from_json:
        points = json.loads(Path(args.from_json).read_text())
        report(points, before, plots, list(dict.fromkeys(p["renderer"] for p in points)))
        return
    import bpy

    import boxmarch
    from bench.common import table
    from boxmarch import preview

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    preview.ensure_gpu_context()
    began = time.perf_counter()
    points = []
    budget = TRIANGLE_BUDGET // 6 if args.quick else TRIANGLE_BUDGET
    with tempfile.TemporaryDirectory(prefix="bench-curve-") as folder:
        for name, scene in curve_scenes(args.quick).items():
            start = time.perf_counter()
            reference = exact_picture(scene)
            print(f"{name}: {len(scene.origins):,} links, {scene.width} x {scene.height}, reference "
                  f"{time.perf_counter() - start:.0f} s, {100 * reference.covered.mean():.1f} % covered", flush=True)
            levels = mesh_levels(scene, budget)
            if "llvmpipe" in args.renderers:
                points += llvmpipe_points(bpy, name, scene, reference, levels)
            if "SwiftShader" in args.renderers:
                points += swiftshader_points(bpy, name, scene, reference, levels, folder)
            print(table(HEADERS, table_rows([p for p in points if p["scene"] == name])), flush=True)
    import gpu

    print(f"\n{gpu.platform.renderer_get()} (bpy {bpy.app.version_string}); three.js r111 on SwiftShader; "
          f"median of {REPEATS} frames in round robin; {time.perf_counter() - began:.0f} s in all")
    report(points, before, plots, args.renderers)
    if args.json:
        write_json(args.json, points)
    sys.stdout.flush()
    os._exit(0)  # bpy modules with registered add-ons may crash at exit (shared notes)


if __name__ == "__main__":
    main()

"""Viewport preview frame times with and without the GPU-side techniques, in one run.

The scenes of bench_gpu_cost.py that fit a preview mesh (chain down the arm, pile, cloud) and its
pile of 1,000 plain boxes (pile_of_boxes, the preview's default shape BOX; as bench_threejs_cost.py), baked
and drawn by the preview's own draw_object into an offscreen buffer, timed from clear to a 1-pixel
read-back (best of REPEATS frames, wall time and the process's CPU time over all of llvmpipe's
threads, which a busy machine disturbs less). Rows:

* today: depth written undeclared (create-info depth_write ANY), boxes in mesh order, quality 1;
* depth_greater + front to back: depth_write GREATER (Blender 4+ only: 3.4 has no declaration)
  and the preview's octant index orders (draw.FRONT_TO_BACK);
* + occluders: the hidden-box pre-pass (preview/occlusion.py);
* + back faces culled: draw.CULL_BACK_FACES (closed, outward-wound boxes drawn with their far side
  culled, the boxes holding the eye again with both sides);
* + occluders + back faces culled, one pass: the pre-pass, the march in one pass that writes its
  depth (every fragment runs on llvmpipe);
* + resolved passes where 16+ layers deep (Blender 4.2 and later): the marching passes write no
  depth, so the depth test culls before the fragment stage (preview/resolve.py), for objects
  whose boxes lie resolve.MIN_OVERDRAW layers deep or more;
* shipped: what the preview draws by default: the pre-pass only where the boxes lie
  occlusion.MIN_LAYERS layers deep or more (the rows above draw it whatever the depth), the
  resolved passes from resolve.MIN_OVERDRAW; + quality 0.5: the knob (occlusion.occluder_count
  runs no pre-pass below full quality for a marched shape; the presets, solved in closed form,
  ignore the knob and keep it).

* + back faces culled, marched: that row with the scene's preset written as a user's text block
  (``return sdf_preset_NAME(p, box_half);``), which the preview marches where every other row
  solves the preset in closed form (no pre-pass: a user's text has no occluders).

SDF evaluations per covered pixel: counted in the shader (the STEPS output: green = march steps
plus a hit's normal taps, a closed-form hit counting 1, summed over every fragment through an
additive float target), divided by the pixels the shaded image covers.

Pixels changed: pixels whose colour differs from today's by more than 1/255, as a share of the
pixels covered in either image.

    # PyPI bpy (Blender 5.0), EGL (llvmpipe here; a GPU where one is); --size N or WxH (960x540)
    PYTHONPATH=addon python3 -m bench.bench_preview_cost [--size 480] [--scenes pile,cloud] [--sweep]
    blender -b --factory-startup --python bench/bench_preview_cost.py -- [--size 480]   # Debian's Blender 3.4
"""
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

WIDTH, HEIGHT, REPEATS = 480, 480, 5
SCENES = ("chain down the arm", "pile", "cloud", "pile of boxes")
# (label, create-info depth_write, draw.FRONT_TO_BACK, quality, occlusion.ENABLED, draw.CULL_BACK_FACES,
#  resolve.ENABLED, occlusion.MIN_LAYERS): the pre-pass forced whatever the depth of the boxes (0)
#  but in the shipped rows (None: the preview's own)
CONFIGS = (("today", "ANY", False, 1.0, False, False, False, 0.0),
           ("depth_greater + front to back", "GREATER", True, 1.0, False, False, False, 0.0),
           ("+ occluders", "GREATER", True, 1.0, True, False, False, 0.0),
           ("+ back faces culled", "GREATER", True, 1.0, False, True, False, 0.0),
           ("+ occluders + back faces culled, one pass", "GREATER", True, 1.0, True, True, False, 0.0),
           ("+ resolved passes where 16+ layers deep", "GREATER", True, 1.0, True, True, True, 0.0),
           ("shipped: the pre-pass from 2 layers, the resolved passes from 16", "GREATER", True, 1.0, True, True, True,
            None),
           ("shipped + quality 0.5", "GREATER", True, 0.5, True, True, True, None),
           ("+ back faces culled, marched (the preset as a user's text)", "GREATER", True, 1.0, False, True, False, 0.0))
# the rows whose shape is the scene's preset written as a user's text block, which the preview
# marches (a preset itself is solved in closed form, shaders/glsl/raymarch.glsl bm_preset_hit)
MARCHED = {CONFIGS[-1]}


def baked_object(bpy, name, scene):
    from boxmarch import mesh_io, scenes

    origins, rotations, half, sdf, _camera = scene
    arrays = scenes.box_arrays(origins, 2 * half, rotations)
    positions, _edges, face_starts, face_sizes, corner_verts = arrays
    ob = bpy.data.objects.new(name, mesh_io.new_mesh(name, positions, face_starts, face_sizes, corner_verts))
    bpy.context.scene.collection.objects.link(ob)
    for other in bpy.context.scene.objects:
        other.select_set(other == ob)
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.boxmarch.bake(sort_axes_by_extent=True) == {"FINISHED"}  # local x along the link
    ob.boxmarch.preview = True
    ob.boxmarch.sdf = sdf
    return ob


def changed_pixels(image, reference):
    """(pixels whose colour differs from ``reference``'s by more than 1/255, pixels covered in
    either image): the rule of the tables' pixels changed."""
    import numpy as np

    covered = (reference[..., 3] > 0) | (image[..., 3] > 0)
    return int(((np.abs(image - reference).max(-1) > 1 / 255) & covered).sum()), int(covered.sum())


def frame_rows(bpy, name, scene):
    import gpu
    import numpy as np

    from boxmarch import preview
    from boxmarch.preview import draw, occlusion, resolve, shader
    from bench.common import best_of, preview_frame

    ob = baked_object(bpy, name, scene)
    to_clip, to_view, _eye = scene[4]
    projection = to_clip @ np.linalg.inv(to_view)
    offscreen = gpu.types.GPUOffScreen(WIDTH, HEIGHT, format="RGBA32F")

    def frame(read=False):
        return preview_frame(offscreen, ob, to_view, projection, read)

    shipped_min_layers = occlusion.MIN_LAYERS

    preset = ob.boxmarch.sdf
    text = bpy.data.texts.new(f"{name}_marched.glsl")
    text.write(f"float map(vec3 p)\n{{\n  return sdf_preset_{preset.lower()}(p, box_half);\n}}\n")
    ob.boxmarch.user_text = text.name

    def use(config):
        (shader.DEPTH_WRITE, draw.FRONT_TO_BACK, ob.boxmarch.quality, occlusion.ENABLED,
         draw.CULL_BACK_FACES, resolve.ENABLED, min_layers) = config[1:]
        occlusion.MIN_LAYERS = shipped_min_layers if min_layers is None else min_layers
        ob.boxmarch.sdf = "USER" if config in MARCHED else preset

    camera = scene_camera(bpy, to_view)

    # Round robin over the configurations, best of REPEATS each, so a busy machine slows them alike.
    best = {config: float("inf") for config in CONFIGS}
    best_cpu = dict(best)
    images, evaluations = {}, {}
    for config in CONFIGS:
        use(config)
        frame()  # compiles and uploads outside the timing
        images[config] = frame(read=True)
        steps, depth = preview.render(bpy.context.scene, camera, WIDTH, HEIGHT, output="STEPS")
        covered = preview.render(bpy.context.scene, camera, WIDTH, HEIGHT)[1] < 1.0
        evaluations[config] = steps[..., 1][covered].sum() / max(covered.sum(), 1)
    for _ in range(REPEATS):
        for config in CONFIGS:
            use(config)
            cpu = time.process_time()
            best[config] = min(best[config], best_of(1, frame))
            best_cpu[config] = min(best_cpu[config], time.process_time() - cpu)
    today = images[CONFIGS[0]]
    rows = []
    for config in CONFIGS:
        changed, covered = changed_pixels(images[config], today)
        rows.append([name, config[0], f"{evaluations[config]:.1f}", f"{best[config] * 1e3:.0f}",
                     f"{best[CONFIGS[0]] / best[config]:.2f}x",
                     f"{best_cpu[config] * 1e3:.0f}", f"{best_cpu[CONFIGS[0]] / best_cpu[config]:.2f}x",
                     f"{100 * changed / max(covered, 1):.2f}%"])
    (shader.DEPTH_WRITE, draw.FRONT_TO_BACK, occlusion.ENABLED, draw.CULL_BACK_FACES, resolve.ENABLED,
     occlusion.MIN_LAYERS) = ("GREATER", True, True, True, True, shipped_min_layers)
    bpy.data.objects.remove(ob)
    bpy.data.objects.remove(camera)
    return rows


def sweep_rows(bpy, made):
    """Piles of 500 to 4,000 links (the pile's cube and camera) and the other scenes, drawn as
    shipped (back faces culled) without the pre-pass, with it in one pass and with it in the
    resolved passes (occlusion.MIN_LAYERS and resolve.MIN_OVERDRAW set aside): frame times side by
    side, round robin, with mesh_data.layers_over_view."""
    import gpu
    import numpy as np

    from bench.bench_gpu_cost import smaller_piles
    from bench.common import best_of, preview_frame
    from boxmarch.preview import draw, mesh_data, occlusion, resolve

    made.update(smaller_piles(WIDTH, HEIGHT))
    offscreen = gpu.types.GPUOffScreen(WIDTH, HEIGHT, format="RGBA32F")
    kept = occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW
    ways = {"none": (float("inf"), float("inf")), "one pass": (0.0, float("inf")), "resolved": (0.0, 0.0)}
    rows = []
    for name in ("chain down the arm", "cloud", "pile of 500", "pile of 1000", "pile of 2000", "pile"):
        ob = baked_object(bpy, name, made[name])
        to_clip, to_view, _eye = made[name][4]
        projection = to_clip @ np.linalg.inv(to_view)
        best, images = {}, {}
        for way, limits in ways.items():
            occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = limits
            images[way] = preview_frame(offscreen, ob, to_view, projection, read=True)
        mesh = draw.cached_mesh(ob.data.name_full, ob.boxmarch.layout).baked  # read by the frames above
        layers = mesh_data.layers_over_view(mesh.origins, mesh.box_half_extents, to_clip @ np.array(ob.matrix_world),
                                            WIDTH, HEIGHT)
        for _ in range(REPEATS):
            for way, limits in ways.items():
                occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = limits
                best[way] = min(best.get(way, float("inf")), best_of(1, lambda: preview_frame(
                    offscreen, ob, to_view, projection)))
        changed = max(changed_pixels(images[way], images["none"])[0] for way in ways)
        shipped = ("resolved" if layers >= kept[1] else "one pass") if layers >= kept[0] else "none"
        rows.append([name, f"{layers:.1f}", *[f"{best[way] * 1e3:.0f}" for way in ways],
                     f"{best['none'] / best['one pass']:.2f}x", f"{best['one pass'] / best['resolved']:.2f}x",
                     str(changed), shipped])
        bpy.data.objects.remove(ob)
    occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = kept
    return rows


def scene_camera(bpy, to_view):
    """A camera object at bench_gpu_cost's perspective camera (40 degrees, clip 0.1 to 4000) of view
    matrix ``to_view``, for preview.render's STEPS output."""
    import numpy as np
    from mathutils import Matrix

    from bench.bench_gpu_cost import FAR, NEAR

    data = bpy.data.cameras.new("bench camera")
    data.sensor_fit = "VERTICAL"  # bench_gpu_cost's camera: 40 degrees high, whatever the image's width
    data.angle_y, data.clip_start, data.clip_end = np.radians(40.0), NEAR, FAR
    camera = bpy.data.objects.new("bench camera", data)
    bpy.context.scene.collection.objects.link(camera)
    camera.matrix_world = Matrix(np.linalg.inv(to_view).tolist())
    return camera


def main():
    import argparse

    import bpy
    import gpu

    import boxmarch
    from boxmarch import preview
    from bench.bench_gpu_cost import pile_of_boxes, scenes_to_measure
    from bench.common import table

    global WIDTH, HEIGHT
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default=f"{WIDTH}", help="image size in pixels: N (N x N) or WxH (960x540)")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated scene names")
    parser.add_argument("--sweep", action="store_true",
                        help="instead: one pass against the resolved passes on piles of 500 to 4,000 links")
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
    WIDTH, HEIGHT = (int(v) for v in (args.size.split("x") if "x" in args.size else (args.size, args.size)))
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    preview.ensure_gpu_context()
    made = scenes_to_measure(WIDTH, 8, HEIGHT)
    made["pile of boxes"] = pile_of_boxes(WIDTH, HEIGHT)
    if args.sweep:
        rows = sweep_rows(bpy, made)
        print(f"Blender {bpy.app.version_string}, {gpu.platform.renderer_get()}, {WIDTH} x {HEIGHT} px, best of {REPEATS}")
        print(table(["scene", "layers over the view", "no pre-pass ms", "pre-pass, one pass ms", "resolved passes ms",
                     "pre-pass's speed-up", "resolved against one pass", "pixels changed", "shipped"], rows))
        return
    rows = [row for name in args.scenes.split(",") for row in frame_rows(bpy, name, made[name])]
    print(f"Blender {bpy.app.version_string}, {gpu.platform.renderer_get()}, {WIDTH} x {HEIGHT} px, best of {REPEATS}")
    print(table(["scene", "preview", "SDF evals/px", "frame ms", "speed-up", "CPU ms", "CPU speed-up", "pixels changed"],
                rows))
    sys.stdout.flush()


if __name__ == "__main__":
    if not __package__:  # a Blender program runs this file by path: the repository and its add-on first
        sys.path[:0] = [str(HERE.parent), str(HERE.parent / "addon")]
    main()

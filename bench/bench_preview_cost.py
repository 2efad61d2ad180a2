"""Viewport preview frame times with and without the GPU-side techniques, in one run.

The scenes of bench_gpu_cost.py that fit a preview mesh (chain down the arm, pile, cloud), baked
and drawn by the preview's own draw_object into an offscreen buffer, timed from clear to a 1-pixel
read-back (best of REPEATS frames, wall time and the process's CPU time over all of llvmpipe's
threads, which a busy machine disturbs less). Rows:

* today: depth written undeclared (create-info depth_write ANY), boxes in mesh order, quality 1;
* depth_greater: depth_write GREATER (Blender 4+ only: 3.4 has no declaration, so the row repeats
  today's there);
* + front to back: the preview's octant index orders (draw.FRONT_TO_BACK);
* + quality 0.5: the quality knob.

Pixels changed: pixels whose colour differs from today's by more than 1/255, as a share of the
pixels covered in either image.

    PYTHONPATH=addon python3 -m bench.bench_preview_cost   # PyPI bpy (Blender 5.0), EGL llvmpipe here
    blender -b --factory-startup --python bench/bench_preview_cost.py   # Debian's Blender 3.4
"""
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

SIZE, REPEATS = 480, 5
SCENES = ("chain down the arm", "pile", "cloud")
# (label, create-info depth_write, draw.FRONT_TO_BACK, quality)
CONFIGS = (("today", "ANY", False, 1.0), ("depth_greater", "GREATER", False, 1.0),
           ("depth_greater + front to back", "GREATER", True, 1.0),
           ("depth_greater + front to back + quality 0.5", "GREATER", True, 0.5))


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


def frame_rows(bpy, name, scene):
    import gpu
    import numpy as np

    from boxmarch.preview import draw, shader
    from bench.common import best_of, preview_frame

    ob = baked_object(bpy, name, scene)
    to_clip, to_view, _eye = scene[4]
    projection = to_clip @ np.linalg.inv(to_view)
    offscreen = gpu.types.GPUOffScreen(SIZE, SIZE, format="RGBA32F")

    def frame(read=False):
        return preview_frame(offscreen, ob, to_view, projection, read)

    def use(config):
        shader.DEPTH_WRITE, draw.FRONT_TO_BACK, ob.boxmarch.quality = config[1:]

    # Round robin over the configurations, best of REPEATS each, so a busy machine slows them alike.
    best = {config: float("inf") for config in CONFIGS}
    best_cpu = dict(best)
    images = {}
    for config in CONFIGS:
        use(config)
        frame()  # compiles and uploads outside the timing
        images[config] = frame(read=True)
    for _ in range(REPEATS):
        for config in CONFIGS:
            use(config)
            cpu = time.process_time()
            best[config] = min(best[config], best_of(1, frame))
            best_cpu[config] = min(best_cpu[config], time.process_time() - cpu)
    today = images[CONFIGS[0]]
    rows = []
    for config in CONFIGS:
        covered = (today[..., 3] > 0) | (images[config][..., 3] > 0)
        changed = (np.abs(images[config] - today).max(-1) > 1 / 255) & covered
        rows.append([name, config[0], f"{best[config] * 1e3:.0f}", f"{best[CONFIGS[0]] / best[config]:.2f}x",
                     f"{best_cpu[config] * 1e3:.0f}", f"{best_cpu[CONFIGS[0]] / best_cpu[config]:.2f}x",
                     f"{100 * changed.sum() / max(covered.sum(), 1):.2f}%"])
    shader.DEPTH_WRITE, draw.FRONT_TO_BACK = "GREATER", True
    bpy.data.objects.remove(ob)
    return rows


def main():
    import bpy
    import gpu

    import boxmarch
    from boxmarch import preview
    from bench.bench_gpu_cost import scenes_to_measure
    from bench.common import table

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    preview.ensure_gpu_context()
    made = scenes_to_measure(SIZE, 8)
    rows = [row for name in SCENES for row in frame_rows(bpy, name, made[name])]
    print(f"Blender {bpy.app.version_string}, {gpu.platform.renderer_get()}, {SIZE} x {SIZE} px, best of {REPEATS}")
    print(table(["scene", "preview", "frame ms", "speed-up", "CPU ms", "CPU speed-up", "pixels changed"], rows))
    sys.stdout.flush()


if __name__ == "__main__":
    if not __package__:  # a Blender program runs this file by path: the repository and its add-on first
        sys.path[:0] = [str(HERE.parent), str(HERE.parent / "addon")]
    main()

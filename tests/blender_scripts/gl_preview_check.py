"""Run in the bpy module: scenes of the GPU benchmarks (bench/bench_gpu_cost.py) drawn by the
viewport preview offscreen (preview.render), saved beside what bench/gpu_frame_data.py writes for
bench/gl_preview.py to draw the same object outside Blender (tests/test_gl_preview.py compares).

Usage: python3 gl_preview_check.py -- PACKAGE_PARENT REPOSITORY OUT_FOLDER
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path[:0] = [argv[0], argv[1]]
out_folder = argv[2]

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import preview  # noqa: E402
from boxmarch.preview import mesh_data  # noqa: E402
from bench import gpu_frame_data  # noqa: E402
from bench.bench_gpu_cost import scenes_to_measure  # noqa: E402
from bench.bench_preview_cost import baked_object, scene_camera  # noqa: E402

W, H = 192, 108
boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
made = scenes_to_measure(W, 8, H)
for name in ("pile", "chain down the arm"):
    ob = baked_object(bpy, name, made[name])
    ob.color = gpu_frame_data.BASE_COLOR  # the colour the benchmark's uniform block carries
    to_clip, to_view, _eye = made[name][4]
    camera = scene_camera(bpy, to_view)
    rgba, depth = preview.render(bpy.context.scene, camera, W, H)
    arrays = gpu_frame_data.preview_arrays(mesh_data.read_baked(ob.data), ob.boxmarch, to_clip, to_view)
    np.savez(os.path.join(out_folder, name.replace(" ", "_") + ".npz"), blender_rgba=rgba, blender_depth=depth,
             size=np.array([W, H]), **arrays)
    bpy.data.objects.remove(ob)
    bpy.data.objects.remove(camera)
sys.stdout.flush()
os._exit(0)  # bpy modules with registered add-ons may crash at exit (docs: shared notes)

"""Run inside a Blender program with a window (under Xvfb): the preview's draw handler in the real
3D viewport. Baked boxes in a pure red object colour are screenshot with the preview off and on;
only the raymarched shapes can put red pixels on screen (the object itself is drawn as wire).
Usage: blender --factory-startup --python viewport_check.py -- PACKAGE_PARENT OUT_JSON SHOT_PNG"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from window_harness import arguments, run_in_window  # noqa: E402

argv = arguments()

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402
from boxmarch.preview import draw  # noqa: E402

bpy.context.preferences.view.show_splash = False
boxmarch.register()


def red_pixels(path, region):
    """Red pixels of the 3D viewport's main region in a screenshot of the window."""
    image = bpy.data.images.load(path)
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    rgb = pixels.reshape(height, width, 4)[region.y:region.y + region.height, region.x:region.x + region.width, :3]
    return int(((rgb[..., 0] > 0.35) & (rgb[..., 1] < 0.15) & (rgb[..., 2] < 0.15)).sum())


def check(report):
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region):
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
        arrays, *_ = scenes.random_boxes(20, seed=3, spread=3.0, size_range=(0.6, 1.5))
        ob = bpy.data.objects.new("boxes", mesh_io.new_mesh("boxes", arrays[0], *arrays[2:]))
        bpy.context.scene.collection.objects.link(ob)
        bpy.context.view_layer.update()
        ob.select_set(True)
        bpy.context.view_layer.objects.active = ob
        assert bpy.ops.boxmarch.bake() == {"FINISHED"}
        ob.color = (1.0, 0.0, 0.0, 1.0)
        ob.boxmarch.sdf = "SPHERE"
        space = area.spaces.active
        space.shading.type = "SOLID"
        # red things Blender draws itself: the x axis line, the 3D cursor, the navigation gizmo
        space.overlay.show_axis_x = space.overlay.show_axis_y = False
        space.overlay.show_cursor = False
        space.show_gizmo = False
        space.region_3d.view_distance = 14.0
        ob.select_set(False)
        counts = {}
        for state in (False, True):
            ob.boxmarch.preview = state
            bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
            bpy.ops.screen.screenshot(filepath=argv[2] if state else argv[2] + ".off.png")
            counts[str(state)] = red_pixels(argv[2] if state else argv[2] + ".off.png", region)
        report["red_pixels"] = counts
        report["display_type"] = ob.display_type
        report["errors"] = dict(draw.errors)


run_in_window(check, argv[1])

"""Takes docs/preview.png: a screenshot of Blender's real window (Debian's Blender under Xvfb) with
the raymarch preview on: a chain of links, tori, spheres (with the decoded-vector overlay) and
rounded boxes baked from plain boxes, a user SDF from a text block, and an ordinary ground plane
they sink into.
Usage: xvfb-run -a -s "-screen 0 1280x720x24" blender --factory-startup --python
       scripts/preview_screenshot.py -- PACKAGE_PARENT OUT.png"""
import math
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import numpy as np  # noqa: E402

bpy.context.preferences.view.show_splash = False

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402

boxmarch.register()


def baked_object(name, centres, sizes, rotations, sdf, location, color, **settings):
    arrays = scenes.box_arrays(centres, sizes, rotations)
    mesh = mesh_io.new_mesh(name, arrays[0], *arrays[2:])
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = location
    ob.color = color
    bpy.context.view_layer.update()  # the new object gets its view-layer base (selectable) here
    for other in bpy.context.view_layer.objects:
        other.select_set(other == ob)
    bpy.context.view_layer.objects.active = ob
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}  # every default, as a user bakes
    ob.boxmarch.sdf = sdf
    for key, value in settings.items():
        setattr(ob.boxmarch, key, value)
    ob.boxmarch.preview = True
    return ob


def turn(axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    return {"x": [[1, 0, 0], [0, c, -s], [0, s, c]], "y": [[c, 0, s], [0, 1, 0], [-s, 0, c]],
            "z": [[c, -s, 0], [s, c, 0], [0, 0, 1]]}[axis]


def build():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    bpy.ops.mesh.primitive_plane_add(size=30.0, location=(0.0, 0.0, 0.0))
    links = 9
    centres = [[0.78 * i - 3.2, 0.0, 0.9] for i in range(links)]
    rotations = [turn("x", math.pi / 2 * (i % 2)) for i in range(links)]
    baked_object("Chain", centres, [1.2, 0.6, 0.14], rotations, "LINK", (0, -1.5, 0), (0.85, 0.65, 0.3, 1))
    rng = np.random.default_rng(5)
    n = 14
    centres = np.c_[rng.uniform(-4, 4, n), rng.uniform(0.5, 5, n), rng.uniform(0.1, 1.2, n)]
    sizes = rng.uniform(0.6, 1.6, (n, 3))
    sizes[:, 2] *= 0.4
    baked_object("Tori", centres, sizes, scenes.random_rotations(n, rng), "TORUS", (0, 0, 0), (0.35, 0.6, 0.9, 1))
    centres = np.c_[rng.uniform(-4, 4, n), rng.uniform(-5, -2.5, n), rng.uniform(-0.2, 0.6, n)]
    baked_object("Spheres", centres, rng.uniform(0.5, 1.3, (n, 3)), scenes.random_rotations(n, rng), "SPHERE",
                 (0, 0, 0), (0.9, 0.35, 0.3, 1), show_vectors=True)
    centres = [[5.5, -3 + 2.2 * i, 0.7] for i in range(4)]
    baked_object("RoundedBoxes", centres, [1.4, 1.0, 1.4], scenes.random_rotations(4, rng), "ROUNDED_BOX",
                 (0, 0, 0), (0.55, 0.8, 0.45, 1))
    text = bpy.data.texts.new("blob.glsl")
    text.write("float map(vec3 p)\n{\n  float s = sd_sphere(p - vec3(0.0, 0.0, 0.2 * box_half.z), 0.7 * min3(box_half));\n"
               "  float ring = sd_torus(p, 0.8 * min(box_half.x, box_half.y), 0.15 * box_half.z);\n"
               "  return op_smooth_union(s, ring, 0.3 * min3(box_half));\n}\n")
    centres = [[-6.0, -2 + 2.5 * i, 1.0] for i in range(3)]
    baked_object("UserSDF", centres, [1.8, 1.8, 1.2], [np.eye(3)] * 3, "USER", (0, 0, 0), (0.8, 0.8, 0.85, 1),
                 user_text=text.name)


def view3d():
    window = bpy.context.window_manager.windows[0]
    for area in window.screen.areas:
        if area.type == "VIEW_3D":
            region = next(r for r in area.regions if r.type == "WINDOW")
            return window, area, region
    raise RuntimeError("no 3D viewport")


def shoot():
    window, area, region = view3d()
    space = area.spaces.active
    space.overlay.show_floor = False
    space.overlay.show_axis_x = space.overlay.show_axis_y = False
    space.shading.type = "SOLID"
    space.show_region_ui = False
    space.show_region_toolbar = False
    space.show_gizmo = False
    r3d = space.region_3d
    r3d.view_perspective = "PERSP"
    r3d.view_location = (0.0, 0.0, 0.5)
    r3d.view_distance = 14.0
    from mathutils import Euler

    r3d.view_rotation = Euler((math.radians(62), 0.0, math.radians(28))).to_quaternion()
    for ob in bpy.context.view_layer.objects:
        ob.select_set(False)
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=2)
        # the whole window: screenshot_area wrote a 1 x 1 image under Xvfb here (Blender 3.4)
        bpy.ops.screen.screenshot(filepath=out_path)
    print("preview_screenshot: wrote", out_path)
    bpy.ops.wm.quit_blender()


def start():
    try:
        window, area, region = view3d()
        with bpy.context.temp_override(window=window, area=area, region=region):
            build()
        bpy.app.timers.register(shoot_safely, first_interval=1.0)
    except Exception:
        import traceback

        traceback.print_exc()
        bpy.ops.wm.quit_blender()


def shoot_safely():
    try:
        shoot()
    except Exception:
        import traceback

        traceback.print_exc()
        bpy.ops.wm.quit_blender()


bpy.app.timers.register(start, first_interval=0.5)

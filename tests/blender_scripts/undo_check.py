"""Run inside a Blender program with a window (under Xvfb): bake and undo, in Object and Edit
Mode, and record whether the baked layers exist at each step.
Usage: blender --factory-startup --python undo_check.py -- PACKAGE_PARENT OUT_JSON"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from window_harness import arguments, run_in_window  # noqa: E402

argv = arguments()

import bpy  # noqa: E402

import boxmarch  # noqa: E402

bpy.context.preferences.view.show_splash = False
boxmarch.register()


def baked(_ob=None):
    # Looked up by name: undo replaces the datablocks, so old references go stale.
    return "BoxOffset" in bpy.data.objects["Cube"].data.color_attributes


def window_context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return bpy.context.temp_override(window=window, area=area)


def check(report):
    with window_context():
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
        bpy.ops.mesh.primitive_cube_add()
        ob = bpy.context.active_object
        bpy.ops.ed.undo_push(message="cube")
        bpy.ops.boxmarch.bake()
        state = {"after_bake": baked(ob)}
        bpy.ops.ed.undo()
        ob = bpy.context.active_object
        state["after_undo"] = baked(ob)
        report["object_mode"] = state

        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.ed.undo_push(message="select")
        bpy.ops.boxmarch.bake()
        state = {"after_bake": baked(bpy.context.active_object)}
        bpy.ops.ed.undo()
        bpy.ops.object.mode_set(mode="OBJECT")
        state["after_undo"] = baked(bpy.context.active_object)
        report["edit_mode"] = state


run_in_window(check, argv[1])

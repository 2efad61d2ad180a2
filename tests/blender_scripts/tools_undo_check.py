"""Run inside a Blender program with a window (under Xvfb): each submesh tool in Edit Mode, then
undo, recording the mesh before, after and after undo. Also proves the tools run in this Blender.
Usage: blender --factory-startup --python tools_undo_check.py -- PACKAGE_PARENT OUT_JSON"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from window_harness import arguments, run_in_window  # noqa: E402

argv = arguments()

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402

bpy.context.preferences.view.show_splash = False
boxmarch.register()


def build_mesh():
    """Three boxes, a copy of box 0 moved by 1e-6, and a box whose +x face has its own copies
    of two corners (merge removes 2 vertices); every face its own UV island; a Skin modifier, whose
    radii live outside the generic attributes."""
    boxes = scenes.box_arrays(np.array([[0.0, 0, 0], [3, 0, 0], [6, 0, 1], [1e-6, 0, 0], [9, 0, 2]]), 1.0, np.eye(3))
    positions, _edges, starts, sizes, corners = boxes
    positions = np.concatenate([positions, positions[[36, 38]] + 1e-5])
    corners = corners.copy()
    corners[4 * 6 * 4 + 4: 4 * 6 * 4 + 8] = [40, 41, 39, 37]  # box 4's +x face: 4->40, 6->41
    mesh = mesh_io.new_mesh("Boxes", positions, starts, sizes, corners)
    mesh.uv_layers.new(name="UVMap")
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    uv = (square[None] + np.arange(30, dtype=np.float32)[:, None, None] * 2).reshape(-1)
    mesh.uv_layers["UVMap"].data.foreach_set("uv", uv)  # 3.4: no .uv collection yet
    ob = bpy.data.objects.new("Boxes", mesh)
    bpy.context.scene.collection.objects.link(ob)
    ob.modifiers.new("Skin", "SKIN")
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    return ob


def snapshot():
    """The edit mesh as the user sees it (read through bmesh: a small mesh, a test)."""
    import bmesh

    # Looked up by name: undo replaces the datablocks, so old references go stale.
    bm = bmesh.from_edit_mesh(bpy.data.objects["Boxes"].data)
    uv_layer = bm.loops.layers.uv["UVMap"]
    uv_sum = sum(loop[uv_layer].uv[0] + loop[uv_layer].uv[1] for face in bm.faces for loop in face.loops)
    return {"vertices": len(bm.verts), "faces": len(bm.faces), "selected": sum(v.select for v in bm.verts),
            "uv_sum": round(float(uv_sum), 4), "skin_layers": len(bm.verts.layers.skin)}


def window_context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return bpy.context.temp_override(window=window, area=area)


TOOLS = [("select_linked_submeshes", {}, "one"), ("select_linked_across", {"epsilon": 1e-4}, "one"),
         ("dedup_submeshes", {}, "all"), ("merge_by_distance_submeshes", {"distance": 1e-3}, "all"),
         ("pack_uv_by_z", {}, "all")]


def check(report):
    report.update({"version": list(bpy.app.version), "tools": {}})
    with window_context():
        for name, args, selection in TOOLS:
            if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
                bpy.ops.object.mode_set(mode="OBJECT")
            for ob in list(bpy.data.objects):
                bpy.data.objects.remove(ob)
            ob = build_mesh()
            select = np.zeros(len(ob.data.vertices), bool)
            select[0 if selection == "one" else slice(None)] = True
            ob.data.vertices.foreach_set("select", select)
            for collection in (ob.data.edges, ob.data.polygons):  # new elements come selected
                collection.foreach_set("select", np.zeros(len(collection), bool))
            bpy.ops.ed.undo_push(message="mesh " + name)  # as an add-mesh operator would
            report["running"] = name
            bpy.ops.object.mode_set(mode="EDIT")
            bpy.ops.mesh.select_mode(type="VERT")
            if selection == "all":
                bpy.ops.mesh.select_all(action="SELECT")
            bpy.ops.ed.undo_push(message="before " + name)
            state = {"before": snapshot()}
            state["result"] = list(getattr(bpy.ops.boxmarch, name)(**args))
            # Operators called from a script push no undo step of their own (the UI pushes
            # one after an operator with the UNDO option): push it as the UI would.
            bpy.ops.ed.undo_push(message=name)
            state["after"] = snapshot()
            state["undo_option"] = "UNDO" in getattr(bpy.types, "BOXMARCH_OT_" + name).bl_options
            bpy.ops.ed.undo()
            state["undone"] = snapshot()
            report["tools"][name] = state

        bpy.ops.object.mode_set(mode="OBJECT")
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
        bpy.ops.mesh.primitive_cube_add(size=0.2)
        cube = bpy.context.active_object.name
        bpy.ops.curve.primitive_nurbs_path_add()
        bpy.ops.ed.undo_push(message="curve")
        result = bpy.ops.boxmarch.add_instance_on_curve(instance=cube, spacing=0.5)
        bpy.ops.ed.undo_push(message="instance on curve")
        curve = bpy.context.active_object
        evaluated = curve.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        state = {"result": list(result), "evaluated_vertices": len(mesh.vertices),
                 "modifiers": len(curve.modifiers)}
        evaluated.to_mesh_clear()
        bpy.ops.ed.undo()
        state["modifiers_undone"] = len(bpy.context.active_object.modifiers)
        report["instance_on_curve"] = state


run_in_window(check, argv[1])

"""Run inside a Blender program with a fresh user config: install the add-on from a zip (4.2+: with
scripts/install_extension.py), enable it, bake boxes through the installed copy and write what happened.
Usage: blender -b --factory-startup --python install_check.py -- ZIP OUT_JSON"""
import importlib
import json
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # scripts/
argv = sys.argv[sys.argv.index("--") + 1:]
zip_path, out_path = argv[0], argv[1]
result = {"error": None}
try:
    import bpy  # first: with the bpy module, addon_utils is importable only after it
    import addon_utils
    import numpy as np

    if bpy.app.version >= (4, 2, 0):
        from scripts.install_extension import install  # docs/GETTING_STARTED.md's scripted install

        module_name = install(zip_path)
    else:
        bpy.ops.preferences.addon_install(filepath=zip_path)
        bpy.ops.preferences.addon_enable(module="boxmarch")
        module_name = "boxmarch"
    module = sys.modules[module_name]
    result["module_file"] = module.__file__
    result["enabled"] = addon_utils.check(module_name)[1]
    core = sys.modules[module_name + ".core"]
    result["core_file"] = core._core.__file__
    scenes = importlib.import_module(module_name + ".scenes")
    mesh_io = importlib.import_module(module_name + ".mesh_io")
    bpy.ops.wm.read_homefile(use_empty=True)
    (positions, _, face_starts, face_sizes, corner_verts), centres, sizes, _ = scenes.random_boxes(
        40, seed=2, spread=10.0, size_range=(0.5, 3.0))
    ob = bpy.data.objects.new("Boxes", mesh_io.new_mesh("Boxes", positions, face_starts, face_sizes, corner_verts))
    bpy.context.scene.collection.objects.link(ob)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    result["bake"] = sorted(bpy.ops.boxmarch.bake())
    mesh = ob.data
    colour = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.color_attributes["BoxOffset"].data.foreach_get("color", colour)
    colour = colour.reshape(-1, 4)[corner_verts].astype(np.float64)
    q = np.concatenate([np.array([d.uv[:] for d in mesh.uv_layers[n].data]) for n in ("BoxQuatXY", "BoxQuatZW")], 1)
    f = (colour[:, :3] * 2 - 1) / colour[:, 3:4]
    u, w = q[:, :3], q[:, 3:4]
    origin = positions[corner_verts] + f + 2 * np.cross(u, np.cross(u, f) + w * f)
    box = corner_verts // 8
    result["max_relative_error"] = float((np.linalg.norm(origin - centres[box], axis=1) / (sizes[box].max(1) / 2)).max())
    result["user_scripts"] = bpy.utils.user_resource("SCRIPTS")
    # The raymarch preview of the installed copy: its shaders must have travelled in the zip.
    preview = importlib.import_module(module_name + ".preview")
    sources = importlib.import_module(module_name + ".formats.shader_sources")
    result["shader_dir"] = str(sources.shader_dir())
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    bpy.context.scene.collection.objects.link(camera)
    camera.location = (0.0, -40.0, 0.0)
    camera.rotation_euler = (1.5707963, 0.0, 0.0)
    ob.boxmarch.preview = True
    rgba, _depth = preview.render(bpy.context.scene, camera, 64, 48)
    result["preview_covered"] = float((rgba[..., 3] > 0).mean())
    result["version"] = list(bpy.app.version)
    result["bpy_file"] = bpy.__file__
except Exception:
    result["error"] = traceback.format_exc()
with open(out_path, "w") as f:
    json.dump(result, f)

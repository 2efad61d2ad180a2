"""Run inside a Blender program: BOXES random boxes (tests/conftest.py's random_boxes_object
figures) with smooth faces, and again flattened (tests/helpers/file_vertices.flatten), each
baked and exported with every engine preset and layout into OUT_DIR; OUT_DIR/result.json names
the files ("FACES PRESET LAYOUT" -> file) and Blender's version. tests/test_export_bytes.py counts them.
Usage: blender -b --python export_bytes_check.py -- PACKAGE_PARENT REPOSITORY_ROOT OUT_DIR BOXES"""
import json
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path[:0] = [argv[0], argv[1]]

import bpy  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, scenes  # noqa: E402
from boxmarch.formats import presets  # noqa: E402
from tests.helpers.file_vertices import flatten  # noqa: E402

boxmarch.register()
result = {"version": list(bpy.app.version), "files": {}}
for faces in ("smooth", "flat"):
    bpy.ops.wm.read_homefile(use_empty=True)
    (arrays, *_), = [scenes.random_boxes(int(argv[3]), seed=3, spread=5.0, size_range=(0.5, 1.5))]
    mesh = mesh_io.new_mesh("Boxes", arrays[0], *arrays[2:], edges=arrays[1])
    ob = bpy.data.objects.new("Boxes", mesh)
    bpy.context.scene.collection.objects.link(ob)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    if faces == "flat":
        flatten(bpy, mesh)
    else:  # Blender 3.4 makes new faces flat
        mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    for name, preset in presets.PRESETS.items():
        for layout in () if preset.raw_blend else preset.layouts:
            file_name = f"{faces}_{name}_{layout}{preset.extension}"
            assert bpy.ops.boxmarch.export(filepath=os.path.join(argv[2], file_name), preset=name,
                                           layout=layout) == {"FINISHED"}
            result["files"][f"{faces} {name} {layout}"] = file_name
with open(os.path.join(argv[2], "result.json"), "w") as f:
    json.dump(result, f)

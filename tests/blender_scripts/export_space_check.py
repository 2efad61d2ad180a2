"""Run inside a Blender program: export the turned, scaled and parented skinned rigs of
tests/engine_scene.py (TRANSFORM_CASES) with the GLTF preset, writing CASE.glb and, in
OUT_DIR/result.json, each mesh object's world matrix and the export's report figures.
Usage: blender -b --python export_space_check.py -- PACKAGE_PARENT REPOSITORY_ROOT OUT_DIR"""
import json
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path[:0] = [argv[0], argv[1]]

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from tests.engine_scene import TRANSFORM_CASES, transformed_rig  # noqa: E402

boxmarch.register()
from boxmarch.export import scene  # noqa: E402

result = {"version": list(bpy.app.version), "cases": {}}
for case in TRANSFORM_CASES:
    bpy.ops.wm.read_homefile(use_empty=True)
    ob, _rig = transformed_rig(bpy, case)
    report = scene.export_objects(bpy.context, [ob], "GLTF", os.path.join(argv[2], case + ".glb"))
    result["cases"][case] = {"matrix_world": np.array(ob.matrix_world).tolist(),
                             "transform_error": report["transform_error"], "space": report["meshes"][0]["space"]}
with open(os.path.join(argv[2], "result.json"), "w") as f:
    json.dump(result, f)

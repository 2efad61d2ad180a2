"""Run by tests/test_hostile_export.py: every file writer of the add-on that a caller reaches
(tests/test_hostile_export.py ATOMIC_WRITERS) under a file-size limit (RLIMIT_FSIZE, what
``ulimit -f`` sets, as a full disk would stop a write), each over files that exist already.
Prints one JSON object: {writer: {"error": the exception's type and text or None, "changed":
files whose bytes changed, "added": files that were not there before}}.

    python file_limit_child.py FOLDER
"""
import json
import os
import resource
import sys

import bpy
import numpy as np

import boxmarch
from boxmarch import blend_file, cli, scenes
from boxmarch.export import scene as export_scene
from boxmarch.formats import fbx, fbx_container, glb

LIMIT = 1024  # bytes: every write below is larger
folder = sys.argv[1]


def snapshot():
    out = {}
    for name in os.listdir(folder):
        with open(os.path.join(folder, name), "rb") as f:
            out[name] = f.read()
    return out


def under_limit(names, write, target=None):
    """What write(path of ``target``, default names[0]) leaves under the limit, over earlier
    files of ``names``."""
    for name in names:
        with open(os.path.join(folder, name), "wb") as f:
            f.write(b"an earlier file")
    before = snapshot()
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, hard))
    error = None
    try:
        write(os.path.join(folder, target or names[0]))
    except Exception as exc:  # each writer's own error: what matters is what is left on disk
        error = f"{type(exc).__name__}: {exc}"
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    after = snapshot()
    return {"error": error, "changed": sorted(n for n in before if after.get(n) != before[n]),
            "added": sorted(set(after) - set(before))}


bpy.ops.wm.read_factory_settings(use_empty=False)  # the factory cube, for an FBX with tangents
bpy.ops.export_scene.fbx(filepath=os.path.join(folder, "cube.fbx"), use_tspace=True, use_selection=False)
document = fbx_container.read(os.path.join(folder, "cube.fbx"))
corners = 24
frames = {"Cube": {k: np.tile([0.0, 0.0, 1.0], (corners, 1)) for k in ("NORMAL", "TANGENT", "BINORMAL")}}

bpy.ops.wm.read_factory_settings(use_empty=True)
boxmarch.register()
(arrays, *_), = [scenes.random_boxes(40, seed=3, spread=5.0, size_range=(0.5, 1.5))]
from boxmarch import mesh_io  # noqa: E402  (after register: the package's Blender half)

ob = bpy.data.objects.new("Boxes", mesh_io.new_mesh("Boxes", arrays[0], *arrays[2:]))
bpy.context.scene.collection.objects.link(ob)
ob.select_set(True)
bpy.context.view_layer.objects.active = ob
assert bpy.ops.boxmarch.bake() == {"FINISHED"}

results = {
    "formats.glb.write": under_limit(["a.glb"], lambda path: glb.write(path, {"asset": {"version": "2.0"}}, bytes(4096))),
    "formats.fbx_container.write": under_limit(["b.fbx"], lambda path: fbx_container.write(path, document)),
    "formats.fbx.replace_frame": under_limit([], lambda path: fbx.replace_frame(path, frames), "cube.fbx"),
    "cli.write_json": under_limit(["r.json"], lambda path: cli.write_json(path, {"text": "x" * 4096})),
    "blend_file.save_blend_copy": under_limit(["c.blend"], blend_file.save_blend_copy),
}
for preset, name, beside in (("GLTF", "e.glb", ["e.boxmarch.json"]),
                             ("UNITY", "u.fbx", ["u.boxmarch.json"]),
                             ("GODOT3", "g.glb", ["g.boxmarch.json", "g.boxes.tres", "g.glb.import"]),
                             ("BLENDER", "x.blend", ["x.boxmarch.json"])):
    layout = "NORMAL_FRAME" if preset == "UNITY" else None  # the FBX frame patch (formats/fbx.py) too
    results[f"export.scene.export_objects {preset}"] = under_limit(
        [name, *beside], lambda path: export_scene.export_objects(bpy.context, [ob], preset, path, layout))
print(json.dumps(results, allow_nan=False))
sys.stdout.flush()
os._exit(0)  # bpy 4.2 and 4.5 crash at exit once an add-on registered (docs/PLATFORMS.md)

"""Run by tests/test_hostile_export.py: every file writer of the add-on that a caller reaches
(tests/test_hostile_export.py FILE_WRITERS), each over files that exist already, in one of two
ways. "limit": under a file-size limit (RLIMIT_FSIZE, what ``ulimit -f`` sets, as a full disk
would stop a write). "links": every file it writes is a symbolic link (relative, as
``ln -s targets/NAME NAME`` makes it) to a file in FOLDER/targets. Prints one JSON object:
{writer: {"error": the exception's type and text or None, "changed": files whose bytes changed,
"added": files that were not there before, "links": the links left, {name: where it points},
"earlier": the names of the earlier files (or links) it wrote over}}, files named by their paths
under FOLDER.

    python every_writer_child.py limit|links FOLDER
"""
import json
import os
import resource
import sys

import bpy
import numpy as np

import boxmarch
from boxmarch import blend_file, cli, scenes
from boxmarch.export import outputs_of, scene as export_scene
from boxmarch.formats import fbx, fbx_container, glb
from boxmarch.formats.presets import PRESETS

LIMIT = 1024  # bytes: every write below is larger
mode, folder = sys.argv[1:3]
targets = os.path.join(folder, "targets")
os.makedirs(targets)


def snapshot():
    out = {}
    for root, _folders, names in os.walk(folder):
        for name in names:
            path = os.path.join(root, name)
            if not os.path.islink(path):
                with open(path, "rb") as f:
                    out[os.path.relpath(path, folder)] = f.read()
    return out


def links():
    return {name: os.readlink(os.path.join(folder, name)) for name in sorted(os.listdir(folder))
            if os.path.islink(os.path.join(folder, name))}


def run_writer(names, write, target=None):
    """What write(path of ``target``, default names[0]) leaves, over earlier files of ``names``
    (in "links" mode: links to them)."""
    for name in names:
        path = os.path.join(folder, name)
        if os.path.lexists(path):
            os.remove(path)
        if mode == "links":
            with open(os.path.join(targets, name), "wb") as f:
                f.write(b"an earlier file")
            os.symlink(os.path.join("targets", name), path)
        else:
            with open(path, "wb") as f:
                f.write(b"an earlier file")
    before = snapshot()
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    if mode == "limit":
        resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, hard))
    error = None
    try:
        write(os.path.join(folder, target or names[0]))
    except Exception as exc:  # each writer's own error: what matters is what is left on disk
        error = f"{type(exc).__name__}: {exc}"
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    after = snapshot()
    result = {"error": error, "changed": sorted(n for n in before if after.get(n) != before[n]),
              "added": sorted(set(after) - set(before)), "links": links(), "earlier": names}
    for name in names:  # the next writer starts from a clean folder
        os.remove(os.path.join(folder, name))
        if mode == "links":
            os.remove(os.path.join(targets, name))
    return result


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

if mode == "links":  # the FBX frame patch reads the file it replaces: cube.fbx, moved to targets and linked
    os.replace(os.path.join(folder, "cube.fbx"), os.path.join(targets, "cube.fbx"))
    os.symlink(os.path.join("targets", "cube.fbx"), os.path.join(folder, "cube.fbx"))
results = {
    "formats.glb.write": run_writer(["a.glb"], lambda path: glb.write(path, {"asset": {"version": "2.0"}}, bytes(4096))),
    "formats.fbx_container.write": run_writer(["b.fbx"], lambda path: fbx_container.write(path, document)),
    "formats.fbx.replace_frame": run_writer([], lambda path: fbx.replace_frame(path, frames), "cube.fbx"),
    "cli.write_json": run_writer(["r.json"], lambda path: cli.write_json(path, {"text": "x" * 4096})),
    "blend_file.save_blend_copy": run_writer(["c.blend"], blend_file.save_blend_copy),
}
for preset, name in (("GLTF", "e.glb"), ("UNITY", "u.fbx"), ("GODOT3", "g.glb"), ("BLENDER", "x.blend")):
    # the preset's own layout; for UNITY NORMAL_FRAME, so that the FBX frame patch (formats/fbx.py) runs too
    layout = "NORMAL_FRAME" if preset == "UNITY" else PRESETS[preset].layouts[0]
    results[f"export.scene.export_objects {preset}"] = run_writer(
        [os.path.basename(path) for path in outputs_of(name, preset, layout)],
        lambda path: export_scene.export_objects(bpy.context, [ob], preset, path, layout))
print(json.dumps(results, allow_nan=False))
sys.stdout.flush()
os._exit(0)  # bpy 4.2 and 4.5 crash at exit once an add-on registered (docs/PLATFORMS.md)

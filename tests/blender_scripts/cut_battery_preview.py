"""Run in the bpy module (a fresh Python): the differential battery's scenes (tests/helpers/cut_battery.py)
built, baked, drawn by the viewport preview offscreen plain and with each cut, and exported with
the GLTF preset for three.js; one process for every scene.

SCENES.json: {"scenes": [cut_battery.scene(seed) with each object's "mesh" (cut_battery.mesh_arrays)],  "width", "height", "high_steps",
"preview": [the seeds to draw], "export": [the seeds to export], "plain": {"module.NAME": value}, "cuts": {cut:
{"module.NAME": value}}}. For each seed it writes OUT/scene_SEED.npz: plain_rgba, plain_depth,
CUT_rgba, CUT_depth for every cut, and where a cut changed a pixel, plain_high_* and CUT_high_*
drawn again with max_steps = high_steps; projection (the camera's); skipped (objects the preview
left out). A scene that fails writes OUT/scene_SEED.error (the traceback) instead; a scene the
export refuses writes OUT/scene_SEED.export_error, and is still drawn.

Usage: python3 cut_battery_preview.py -- PACKAGE_PARENT SCENES.json OUT
"""
import json
import os
import sys
import traceback

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
specs = json.loads(open(argv[1]).read())
out = argv[2]

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Matrix, Vector  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview  # noqa: E402
from boxmarch.preview import draw, occlusion, resolve  # noqa: E402

boxmarch.register()
MODULES = {"draw": draw, "occlusion": occlusion, "resolve": resolve}
W, H = specs["width"], specs["height"]
# every cut runs on every scene, whatever the depth of its boxes
occlusion.MIN_LAYERS, resolve.MIN_OVERDRAW = 0.0, 0.0


def switch(settings):
    """Sets each "module.NAME" to its value; {"returns": x} replaces a function by one returning x
    (a negative control's broken cut). Returns what switch() takes to undo it."""
    undo = {}
    for name, value in settings.items():
        module, attribute = name.split(".")
        undo[name] = getattr(MODULES[module], attribute)
        if isinstance(value, dict):
            value = (lambda returned: lambda *args, **kwargs: returned)(value["returns"])
        setattr(MODULES[module], attribute, value)
    return undo


def build(scene_spec):
    """The scene's objects, baked, previewed with its shape and quality; returns (objects, camera)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    objects = []
    for k, (spec, place) in enumerate(zip(scene_spec["objects"], scene_spec["places"])):
        positions, edges, face_starts, face_sizes, corner_verts = (np.asarray(spec["mesh"][name], dtype) for name, dtype in (
            ("positions", np.float32), ("edges", np.int32), ("face_starts", np.int32), ("face_sizes", np.int32),
            ("corner_verts", np.int32)))
        ob = bpy.data.objects.new(f"boxes{k}", mesh_io.new_mesh(f"boxes{k}", positions, face_starts, face_sizes,
                                                                corner_verts, edges=edges))
        scene.collection.objects.link(ob)
        if spec["shapes"] is not None:
            ob.data.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set(
                "value", np.repeat(spec["shapes"], 8).tolist())
        if any(s != 1.0 for s in spec["parent_scale"]):
            parent = bpy.data.objects.new(f"parent{k}", None)
            scene.collection.objects.link(parent)
            parent.scale = spec["parent_scale"]
            ob.parent = parent
        linear = np.diag(spec["parent_scale"]) @ np.asarray(spec["rotation"]) @ np.diag(spec["scale"])
        location = np.diag(1.0 / np.asarray(spec["parent_scale"])) @ (np.asarray(place) - linear @ np.asarray(spec["offset"]))
        ob.location = location.tolist()
        ob.rotation_mode = "QUATERNION"
        ob.rotation_quaternion = Matrix(spec["rotation"]).to_quaternion()
        ob.scale = spec["scale"]
        for other in bpy.context.selected_objects:
            other.select_set(False)
        ob.select_set(True)
        bpy.context.view_layer.objects.active = ob
        result = bpy.ops.boxmarch.bake()
        if result != {"FINISHED"}:
            raise RuntimeError(f"bake of boxes{k}: {result}")
        ob.boxmarch.preview = True
        ob.boxmarch.sdf = "PER_BOX" if scene_spec["shape"] == "PER_BOX" else scene_spec["shape"]
        ob.boxmarch.quality = scene_spec["quality"]
        objects.append(ob)
    c = scene_spec["camera"]
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = c["position"]
    camera.rotation_euler = (Vector(c["target"]) - Vector(c["position"])).to_track_quat("-Z", "Y").to_euler()
    camera.data.sensor_fit = "VERTICAL"
    if "ortho" in c:
        camera.data.type = "ORTHO"
        camera.data.ortho_scale = 2.0 * c["ortho"]
    else:
        camera.data.angle_y = np.radians(c["fov"])
    camera.data.clip_start, camera.data.clip_end = c["near"], c["far"]
    scene.camera = camera
    bpy.context.view_layer.update()
    return objects, camera


def draw_scene(objects, camera, steps=None):
    if steps is not None:
        for ob in objects:
            ob.boxmarch.max_steps = steps
    rgba, depth = preview.render(bpy.context.scene, camera, W, H)
    for ob in objects:
        ob.boxmarch.property_unset("max_steps")
    return rgba, depth


exported, drawn = set(specs["export"]), set(specs["preview"])
for scene_spec in specs["scenes"]:
    seed = scene_spec["seed"]
    try:
        objects, camera = build(scene_spec)
        if seed in exported:
            for ob in bpy.context.scene.objects:
                ob.select_set(ob in objects)
            path = os.path.join(out, f"scene_{seed}.glb")
            try:
                if bpy.ops.boxmarch.export(filepath=path, preset="GLTF") != {"FINISHED"} or not os.path.exists(path):
                    raise RuntimeError("the export wrote nothing")
            except RuntimeError as error:
                open(os.path.join(out, f"scene_{seed}.export_error"), "w").write(str(error))
        if seed in drawn:
            result = {}
            result["view"], result["projection"] = preview.camera_matrices(bpy.context.scene, camera, W, H)
            switch(specs["plain"])
            result["plain_rgba"], result["plain_depth"] = draw_scene(objects, camera)
            result["skipped"] = "; ".join(preview.last_skipped)
            changed = []
            for cut, settings in specs["cuts"].items():
                undo = switch(settings)
                result[f"{cut}_rgba"], result[f"{cut}_depth"] = draw_scene(objects, camera)
                if not (np.array_equal(result[f"{cut}_rgba"], result["plain_rgba"])
                        and np.array_equal(result[f"{cut}_depth"], result["plain_depth"])):
                    changed.append(cut)
                    result[f"{cut}_high_rgba"], result[f"{cut}_high_depth"] = draw_scene(objects, camera,
                                                                                        specs["high_steps"])
                switch(undo)
            if changed:
                result["plain_high_rgba"], result["plain_high_depth"] = draw_scene(objects, camera, specs["high_steps"])
            np.savez_compressed(os.path.join(out, f"scene_{seed}.npz"), **result)
    except Exception:  # one scene's failure is reported; the others still run
        open(os.path.join(out, f"scene_{seed}.error"), "w").write(traceback.format_exc())
    print(f"scene {seed} done", flush=True)

sys.stdout.flush()
os._exit(0)  # PyPI's bpy 4.2/4.5 crash at exit once an add-on registered classes (docs/PLATFORMS.md)

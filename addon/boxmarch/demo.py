"""The README's main job, headless (``python -m boxmarch demo``): build a posed character wearing
chains of links (demo_character) on a ground of pebbles (the scale: ``--count`` boxes, with
duplicates and split corners), run dedup, merge, bake (8-bit and float, then an incremental
re-bake) and pack-uv through the same jobs as the operators, export demo.glb with the GLTF preset
and decode it back in glTF's frame, render demo.png and save demo.blend. cli.py parses the options
and prints the table ``run_demo`` returns."""
from __future__ import annotations

import os
import time

import bpy
import numpy as np

from . import bake_job, blend_file, blender_output, core, demo_character, ensure_registered, mesh_io, scenes, tool_jobs
from .formats import files
from .export.every_engine import ENGINE_PRESETS, engine_outputs, engine_path, export_every_engine
from .formats import glb, layouts, presets, transforms
from .export import scene as export_scene

DEMO_IMAGE_SIZE = demo_character.PICTURE_SIZE
PEBBLE_RADIUS = 14.0  # the ground's pebbles lie this far around the character at most
MAX_COUNT = 1_000_000  # boxes: 8 million vertices, the scale of Instance on Curve's limit


def demo_outputs(folder: str) -> list:
    """Every file the demo writes into ``folder``: demo.glb (GLTF) and one file per engine preset
    (export.every_engine), demo.png, demo.blend."""
    return engine_outputs(folder, "demo") + [os.path.join(folder, "demo.png"), os.path.join(folder, "demo.blend")]


def _pebbles(count, seed):
    """The ground the character stands on, the README's scale: ``count`` pebbles (boxes of varied
    sizes and rotations, half sunk in the ground) within PEBBLE_RADIUS of the character, 5% of them
    translated copies (the copy cache's case), 2% exact duplicates of others (for dedup) and 2%
    with one corner split into two vertices 1e-5 apart (for merge). Returns (object 'Pebbles',
    expected duplicates, expected split corners)."""
    rng = np.random.default_rng(seed)
    duplicates = count // 50
    splits = count // 50
    unique = count - duplicates
    copies = unique // 20
    sizes = rng.uniform(0.08, 0.4, (unique, 3))
    rotations = scenes.random_rotations(unique, rng)
    sizes[-copies:] = sizes[:copies]
    rotations[-copies:] = rotations[:copies]
    radius = PEBBLE_RADIUS * np.sqrt(rng.uniform(0.0, 1.0, unique))  # even over the disc
    angle = rng.uniform(0.0, 2 * np.pi, unique)
    centres = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), rng.uniform(-0.05, 0.05, unique)])
    # Disjoint sets: a box that got both a duplicate and a split corner would leave two nearly
    # equal boxes that neither dedup nor merge removes.
    chosen = rng.permutation(unique)
    twins, split = chosen[:duplicates], chosen[duplicates:duplicates + splits]
    centres = np.concatenate([centres, centres[twins]])
    sizes = np.concatenate([sizes, sizes[twins]])
    rotations = np.concatenate([rotations, rotations[twins]])
    positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, sizes, rotations)
    # Split corner 0 of some boxes: their first face (-x) uses a new vertex 1e-5 away.
    extra = positions[8 * split] + np.float32(1e-5)
    corner_verts[24 * split] = len(positions) + np.arange(splits, dtype=np.int32)
    positions = np.concatenate([positions, extra])
    pebbles = bpy.data.objects.new("Pebbles", mesh_io.new_mesh("Pebbles", positions, face_starts, face_sizes,
                                                               corner_verts))
    bpy.context.scene.collection.objects.link(pebbles)
    return pebbles, duplicates, splits


def _bake_all(meshes, encoding, incremental):
    """Bake every mesh as the bake command does; (seconds, written bakes)."""
    t = time.perf_counter()
    prepared = bake_job.bake_meshes(meshes, mesh_io.BakeSettings(encoding=encoding, incremental=incremental))
    return time.perf_counter() - t, prepared


def _glb_decode_error(path, objects, prepared):
    """Read ``path`` back (boxmarch.formats.glb) and decode every vertex in glTF's frame with the
    shader's formula; worst distance to the baked centre of its submesh put in glTF's frame, over
    that submesh's largest half-extent."""
    preset = presets.PRESETS["GLTF"]
    gltf, binary = glb.read(path)
    by_name = {ob.data.name: (ob.data, bake.result) for ob, bake in zip(objects, prepared)}
    worst = 0.0
    for mesh_entry in gltf["meshes"]:
        mesh, result = by_name[mesh_entry["name"]]
        ours = transforms.target_positions(mesh_io.read_positions(mesh), preset).astype(np.float32)
        centres = transforms.target_positions(result.origins, preset)
        half = result.half_extents.max(axis=1)
        for primitive in mesh_entry["primitives"]:
            a = {k: glb.accessor_array(gltf, binary, i).astype(np.float64) for k, i in primitive["attributes"].items()}
            # The GLTF preset's NORMAL_FRAME layout (docs/ENGINES.md): x = tangent, z = normal.
            x, z = a["TANGENT"][:, :3], a["NORMAL"]
            y = np.cross(z, x) * a["TANGENT"][:, 3:]
            f = np.concatenate([a["TEXCOORD_1"], a["TEXCOORD_2"][:, :1]], axis=1)
            origin = a["POSITION"] + x * f[:, :1] + y * f[:, 1:2] + z * f[:, 2:]
            # The submesh of each file vertex: the Blender vertex at exactly that position, found
            # by sorting (positions are a signed permutation of float32 values, so exact).
            _, group = np.unique(np.concatenate([ours, a["POSITION"].astype(np.float32)]), axis=0, return_inverse=True)
            group = group.reshape(-1)
            vertex_of_group = np.full(group.max() + 1, -1)
            vertex_of_group[group[:len(ours)]] = np.arange(len(ours))
            vertex = vertex_of_group[group[len(ours):]]
            if (vertex < 0).any():
                raise RuntimeError(f"{path} holds a vertex mesh '{mesh.name}' does not have")
            submesh = result.submesh_of_vertex[vertex]
            worst = max(worst, float((np.linalg.norm(origin - centres[submesh], axis=1) / half[submesh]).max()))
    return worst


def _camera():
    """The scene's camera, as demo_character.CAMERA puts it (scripts/threejs_picture.py takes the
    same)."""
    from mathutils import Vector

    data = bpy.data.cameras.new("DemoCamera")
    data.lens = demo_character.CAMERA["lens"]
    camera = bpy.data.objects.new("DemoCamera", data)
    bpy.context.scene.collection.objects.link(camera)
    camera.location = demo_character.CAMERA["location"]
    aim = Vector(demo_character.CAMERA["target"]) - camera.location
    camera.rotation_euler = aim.to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = camera
    return camera


def _preview_picture(objects, path, renderer, progress):
    """Render the preview picture, each object as demo_character.LOOKS has it (the NORMAL_FRAME
    layout, the GLTF preset's, whose frame the pose turns): the GPU raymarch preview when a GPU
    context can be made (or ``renderer`` is 'GPU'), else the CPU reference raymarcher (same
    SDFs, the posed boxes baked from the posed mesh). Returns the method used."""
    from . import preview  # the GPU module: imported only when a picture is made

    scene = bpy.context.scene
    camera = _camera()
    width, height = DEMO_IMAGE_SIZE
    for ob in objects:
        sdf, colour = demo_character.LOOKS[ob.name]
        ob.boxmarch.sdf, ob.boxmarch.layout, ob.color = sdf, "NORMAL_FRAME", (*colour, 1.0)
        ob.boxmarch.preview = True
    rgba, context_lines = None, []
    if renderer != "CPU":
        try:
            with blender_output.captured(2) as context_lines:
                rgba, _depth = preview.render(scene, camera, width, height)
            method = "GPU raymarch preview"
            # Blender's own first GPU context prints three "EGL Error (0x3009): EGL_BAD_MATCH" lines
            # here (bpy 5.0.1 on Mesa llvmpipe; a plain Workbench render prints the same) and then
            # works: the render came back, so they are not passed on.
            context_lines = [line for line in context_lines if not line.startswith("EGL Error")]
        except (SystemError, RuntimeError) as error:  # no GPU context here
            if renderer == "GPU":
                raise
            progress(f"preview: no GPU ({str(error).splitlines()[0]}), using the CPU reference raymarcher")
        for line in context_lines:
            progress(f"Blender: {line}")
    if rgba is None:
        view, projection = preview.camera_matrices(scene, camera, width, height)
        depth = np.ones((height, width), np.float32)
        rgba = np.zeros((height, width, 4), np.float32)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for ob in objects:
            # The boxes as posed: the bake's frames of the armature-deformed mesh (each box moves rigidly).
            posed = ob.evaluated_get(depsgraph).data
            boxes = core.bake(mesh_io.read_positions(posed), *mesh_io.read_topology(posed))
            world = np.array(ob.matrix_world, np.float64)
            core.render_boxes(boxes.origins, boxes.quaternions, boxes.half_extents, projection @ view @ world,
                              view @ world, width, height, sdf=ob.boxmarch.sdf, base_color=tuple(ob.color[:3]),
                              depth=depth, rgba=rgba)
        method = "CPU reference raymarcher"
    image = bpy.data.images.new("boxmarch_demo", width, height, alpha=True)
    try:
        # Over a dark background (the render's background is transparent), rows bottom-up as Blender stores them.
        alpha = np.clip(rgba[::-1, :, 3:4], 0.0, 1.0)
        picture = np.empty((height, width, 4), np.float32)
        picture[..., :3] = np.clip(rgba[::-1, :, :3], 0.0, 1.0) * alpha + np.float32(0.08) * (1.0 - alpha)
        picture[..., 3] = 1.0
        image.pixels.foreach_set(picture.reshape(-1))
        image.file_format = "PNG"

        def save(temp):
            image.filepath_raw = temp
            image.save()
        files.write_atomically(path, save)
    finally:
        bpy.data.images.remove(image)
    return method


def run_demo(count: int, seed: int, folder: str, renderer: str, progress) -> tuple[list, dict]:
    """Run the demo into ``folder`` (made if missing) in a fresh scene; ``progress(text)`` hears
    each step. Returns (table rows [step, time, what, accuracy], report dict)."""
    os.makedirs(folder, exist_ok=True)
    rows = []
    start = time.perf_counter()
    progress(f"building the character and {count:,} pebbles")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ensure_registered()
    pebbles, duplicates, splits = _pebbles(count, seed)
    rig, mannequin, chains = demo_character.build(bpy, bpy.context.scene)
    objects = [pebbles, mannequin, chains]
    rows.append(["build scene", f"{time.perf_counter() - start:.3f} s",
                 f"{len(pebbles.data.vertices):,} pebble vertices; a mannequin of {len(demo_character.BODY)} boxes "
                 f"and {len(chains.data.vertices) // 8} chain links on {len(rig.data.bones)} bones, "
                 f"{len(demo_character.POSE)} of them turned", ""])

    for name, tool, expected in (("dedup", tool_jobs.DeleteDuplicates(tolerance=1e-4),
                                  f"{duplicates} exact duplicates planted"),
                                 ("merge", tool_jobs.MergeByDistance(distance=1e-3), f"{splits} split corners planted")):
        progress(name)
        before = len(pebbles.data.vertices)
        t = time.perf_counter()
        tool_jobs.run_tool(bpy.context, tool, [pebbles])  # where the duplicates and splits were planted
        rows.append([name, f"{time.perf_counter() - t:.3f} s",
                     f"{before:,} -> {len(pebbles.data.vertices):,} pebble vertices", expected])

    meshes = [ob.data for ob in objects]
    for encoding in ("BYTE_COLOR", "FLOAT_COLOR"):
        progress(f"baking ({encoding})")
        seconds, prepared = _bake_all(meshes, encoding, incremental=False)
        rs = [p.result for p in prepared]
        channels = prepared[0].report["uv_channels"]
        rows.append([f"bake {encoding}", f"{seconds:.3f} s",
                     f"{sum(r.baked for r in rs):,} submeshes, {sum(r.cache_hits for r in rs):,} cache hits, "
                     f"{sum(r.degenerate for r in rs)} degenerate",
                     f"worst decode error {max(r.max_relative_error for r in rs):.2e} of half-extent "
                     f"(UV channels {channels[0]}, {channels[1]})"])
    float_bakes = prepared
    progress("re-baking unchanged geometry")
    seconds, prepared = _bake_all(meshes, "FLOAT_COLOR", incremental=True)
    rows.append(["re-bake (incremental)", f"{seconds:.3f} s",
                 f"{sum(p.result.unchanged for p in prepared):,} unchanged submeshes skipped", ""])

    progress("packing UVs by height")
    t = time.perf_counter()
    tool_jobs.run_tool(bpy.context, tool_jobs.PackUvByZ(uv_map="UVMap"), objects)
    rows.append(["pack-uv", f"{time.perf_counter() - t:.3f} s", "UVMap islands in rows by Z", ""])

    progress("exporting demo.glb (GLTF preset)")
    glb_path = os.path.abspath(engine_path(folder, "demo", "GLTF"))
    t = time.perf_counter()
    report = export_scene.export_objects(bpy.context, objects, "GLTF", glb_path)
    seconds = time.perf_counter() - t
    worst = _glb_decode_error(glb_path, objects, float_bakes)
    written = " + ".join(os.path.basename(p) for p in report["files"][1:])
    rows.append(["export demo.glb (GLTF)", f"{seconds:.3f} s",
                 f"layout {report['layout']}: {os.path.getsize(glb_path) / 1e6:.1f} MB + {written}",
                 f"read back: worst decode error {worst:.2e} of half-extent in glTF's frame"])

    progress("exporting for the other engines")
    for name in ENGINE_PRESETS[1:]:
        preset = presets.PRESETS[name]
        # A preset none of whose layouts skinning carries (Unreal's) gets the pebbles alone.
        carries_skin = any(layouts.LAYOUTS[layout].skin_safe for layout in preset.layouts)
        exported = objects if carries_skin else [pebbles]
        engine, = export_every_engine(bpy.context, exported, os.path.abspath(folder), "demo", [name])
        lost = engine["default_import_error"]
        written = [os.path.basename(p) for p in engine["files"]]
        if preset.writes_godot3_import:  # the export wrote the import settings that keep float32
            settings = next(name for name in written if name.endswith(".import"))
            accuracy = f"float32 in Godot 3 with {settings} (its default import loses {lost:.1e})"
        elif lost:
            accuracy = f"default import loses {lost:.1e} of half-extent: {preset.import_fix}"
        else:
            accuracy = "float32 in the engine"
        left_out = "" if carries_skin else " (the pebbles alone: no layout of its carries a skinned frame)"
        rows.append([f"export {name}", f"{engine['seconds']:.3f} s",
                     f"layout {engine['layout']}: {' + '.join(written)}{left_out}", accuracy])

    png_path = os.path.abspath(os.path.join(folder, "demo.png"))
    progress("rendering demo.png")
    t = time.perf_counter()
    method = _preview_picture(objects, png_path, renderer, progress)
    rows.append(["preview demo.png", f"{time.perf_counter() - t:.3f} s",
                 f"{DEMO_IMAGE_SIZE[0]} x {DEMO_IMAGE_SIZE[1]}, {method}", ""])

    path = blend_file.save_blend_copy(os.path.join(folder, "demo.blend"))
    rows.append(["total", f"{time.perf_counter() - start:.3f} s", f"wrote {path}", ""])
    report = {"ok": True, "command": "demo", "count": count, "blend": path, "glb": glb_path, "png": png_path,
              "preview": method, "glb_max_relative_error": worst, "rows": rows,
              "links": len(chains.data.vertices) // 8, "bones": len(rig.data.bones),
              "blender": bpy.app.version_string}
    return rows, report

"""Command line of boxmarch: the add-on's work from scripts and pipelines.

Two forms run the same commands:

    python -m boxmarch COMMAND [FILE.blend] [options]                     (a Python with bpy)
    blender --background FILE.blend --python-expr "import boxmarch.cli; boxmarch.cli.main()" -- COMMAND [options]

Commands: bake, dedup, merge, pack-uv, export, pipeline (chains them), demo. They work on the
objects named with --objects, or on every mesh object of the file. --out writes the result as a
new .blend, --json a machine-readable report; both appear only complete (written under a
temporary name, then renamed). Progress goes to stderr, the result table to stdout. Exit codes: 0
success, 2 bad arguments or input (one line saying why), 1 internal error. docs/CLI.md has the
reference.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

# Operators the cleanup commands run, by id (they live in boxmarch.operators): command -> (id,
# {command-line option: operator property}).
CLEANUP_OPERATORS = {
    "dedup": ("dedup_submeshes", {"tolerance": "tolerance"}),
    "merge": ("merge_by_distance_submeshes", {"distance": "distance"}),
    "pack-uv": ("pack_uv_by_z", {"padding": "padding", "max_per_row": "max_per_row",
                                 "lock_overlapping": "lock_overlapping", "uv_map": "uv_map"}),
}
PIPELINE_STEPS = ("dedup", "merge", "bake", "pack-uv", "export")


class InputError(Exception):
    """Bad arguments or input: exit code 2 with this one-line message."""


class MissingFeature(Exception):
    """An operator this command needs is not part of this build: exit code 1."""


def _progress(message: str) -> None:
    print(f"[boxmarch] {message}", file=sys.stderr, flush=True)


def _table(headers, rows) -> str:
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    fmt = lambda cells: "| " + " | ".join(str(c).ljust(w) for c, w in zip(cells, widths)) + " |"
    return "\n".join([fmt(headers), "|" + "|".join("-" * (w + 2) for w in widths) + "|", *map(fmt, rows)])


def _write_atomically(path: str, write) -> str:
    """Call write(temporary path) next to ``path``, then rename it onto ``path``; on failure
    remove the temporary file and leave ``path`` as it was."""
    path = os.path.abspath(path)
    folder = os.path.dirname(path)
    if not os.path.isdir(folder):
        raise InputError(f"folder '{folder}' does not exist")
    root, ext = os.path.splitext(os.path.basename(path))
    temp = os.path.join(folder, f".{root}.boxmarch-partial{ext}")
    try:
        write(temp)
        os.replace(temp, path)
    finally:
        if os.path.exists(temp):
            os.remove(temp)
    return path


def _check_outputs(bpy, args, steps) -> None:
    """Every check on the output paths, run before anything is written (docs/CLI.md): each
    folder exists and is writable, no output is a folder, the input .blend or another output,
    --out names a .blend and --to carries the preset's extension."""
    outputs = []
    if getattr(args, "out", None):
        if not args.out.lower().endswith(".blend"):
            raise InputError(f"--out must name a .blend file, got '{args.out}'")
        outputs.append(("--out", args.out))
    if "export" in steps and getattr(args, "to", None):
        from .export.transforms import PRESETS

        extension = PRESETS[args.preset].extension
        if not args.to.lower().endswith(extension):
            raise InputError(f"--preset {args.preset} writes a {extension} file: --to must end in {extension}, "
                             f"got '{args.to}'")
        outputs.append(("--to", args.to))
    if getattr(args, "json", None):
        outputs.append(("--json", args.json))
    inputs = {os.path.abspath(p) for p in (getattr(args, "blend", None), bpy.data.filepath if bpy else None) if p}
    seen = {}
    for option, path in outputs:
        full = os.path.abspath(path)
        folder = os.path.dirname(full)
        if not os.path.isdir(folder):
            raise InputError(f"{option}: folder '{folder}' does not exist")
        if os.path.isdir(full):
            raise InputError(f"{option}: '{path}' is a folder")
        if not os.access(folder, os.W_OK | os.X_OK) or (os.path.exists(full) and not os.access(full, os.W_OK)):
            raise InputError(f"{option}: cannot write '{full}' (permission denied)")
        if any(os.path.exists(full) and os.path.exists(i) and os.path.samefile(full, i) or full == i for i in inputs):
            raise InputError(f"{option} '{path}' is the input file, which is never written: choose another path")
        if full in seen:
            raise InputError(f"{option} and {seen[full]} name the same file '{path}'")
        seen[full] = option


def _check_cleanup_options(bpy, args, steps) -> None:
    """Cleanup options outside what the operator accepts are refused (the operator would clamp
    them silently, and the report would record the unclamped value)."""
    for command in steps:
        if command not in CLEANUP_OPERATORS:
            continue
        op_id, options = CLEANUP_OPERATORS[command]
        if not hasattr(bpy.types, "BOXMARCH_OT_" + op_id):
            continue  # step_cleanup says it is missing
        props = getattr(bpy.ops.boxmarch, op_id).get_rna_type().properties
        for option, prop in options.items():
            value = getattr(args, option, None)
            if value is None or prop not in props or props[prop].type not in ("FLOAT", "INT"):
                continue
            lo, hi = props[prop].hard_min, props[prop].hard_max
            if not (math.isfinite(value) and lo <= value <= hi):
                raise InputError(f"--{option.replace('_', '-')} must be a finite number in [{lo:g}, {hi:g}], "
                                 f"got {value!r}")


def _save_blend(bpy, path: str) -> str:
    if not path.lower().endswith(".blend"):
        raise InputError(f"--out must name a .blend file, got '{path}'")
    return _write_atomically(path, lambda temp: bpy.ops.wm.save_as_mainfile(filepath=temp, copy=True,
                                                                             check_existing=False))


def _write_json(path: str, report: dict) -> None:
    def write(temp):
        with open(temp, "w") as f:
            json.dump(report, f, indent=2, default=float)
    _write_atomically(path, write)


# ---------------------------------------------------------------------------------------------
# Scene set-up shared by the commands


def _ensure_registered(bpy) -> None:
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        from . import register  # relative: installed as an extension the package is bl_ext.*.boxmarch

        register()


def _open(bpy, args) -> None:
    """Open FILE when given (checked first: a missing or non-.blend file is bad input)."""
    if getattr(args, "blend", None):
        path = os.path.abspath(args.blend)
        if not os.path.isfile(path):
            raise InputError(f"no such file: {args.blend}")
        with open(path, "rb") as f:
            head = f.read(7)
        if head != b"BLENDER" and not head.startswith((b"\x1f\x8b", b"\x28\xb5\x2f\xfd")):  # plain, gzip, zstd
            raise InputError(f"{args.blend} is not a .blend file")
        _progress(f"opening {path}")
        try:
            bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
        except RuntimeError as error:
            raise InputError(f"cannot open {args.blend}: {str(error).strip().splitlines()[-1]}") from None
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    _ensure_registered(bpy)


def _objects(bpy, args):
    """The objects named with --objects (each must exist and be a mesh), else every mesh object
    of the scene; selects exactly them (operators skip hidden objects: hidden ones are shown,
    and hidden again by _run_steps) and makes the first active."""
    scene_objects = bpy.context.view_layer.objects
    if args.objects:
        objects = []
        for name in args.objects:
            ob = bpy.data.objects.get(name)
            if ob is None:
                raise InputError(f"no object named '{name}' in the file")
            if ob.type != "MESH":
                raise InputError(f"object '{name}' is a {ob.type.lower()}, not a mesh")
            if scene_objects.get(name) is None:
                raise InputError(f"object '{name}' is not in the current scene's view layer")
            objects.append(ob)
    else:
        objects = [ob for ob in scene_objects if ob.type == "MESH"]
        if not objects:
            raise InputError("the file has no mesh objects")
    for ob in scene_objects:
        ob.select_set(False)
    for ob in objects:
        ob.hide_set(False)
        ob.select_set(True)
    scene_objects.active = objects[0]
    return objects


def _meshes(objects):
    return list({ob.data.name_full: ob.data for ob in objects}.values())


# ---------------------------------------------------------------------------------------------
# Steps: each works on the selected objects and returns a report dict


def step_bake(bpy, objects, args) -> dict:
    from . import mesh_io

    settings = mesh_io.BakeSettings(
        angle_epsilon=args.angle_epsilon, origin=args.origin, encoding=args.encoding, domain=args.domain,
        axis_turn=args.axis_turn, sort_axes_by_extent=args.sort_axes_by_extent, use_cache=not args.no_cache,
        incremental=not args.full)
    meshes = _meshes(objects)
    start = time.perf_counter()
    try:  # every mesh is computed before any is written, as the operator does
        prepared = []
        for i, mesh in enumerate(meshes):
            _progress(f"bake: computing {mesh.name} ({i + 1}/{len(meshes)}, {len(mesh.vertices):,} vertices)")
            prepared.append(mesh_io.prepare_bake(mesh, settings))
    except mesh_io.BakeInputError as error:
        raise InputError(f"nothing baked: {error}") from None
    reports = [bake.write() for bake in prepared]
    seconds = time.perf_counter() - start
    warnings = mesh_io.modifier_warnings(objects)
    for warning in warnings:
        _progress(f"WARNING: {warning}")
    totals = {key: sum(r[key] for r in reports)
              for key in ("submeshes", "baked", "cache_hits", "unchanged", "degenerate")}
    return {"step": "bake", "seconds": seconds, **totals, "warnings": warnings, "skipped": totals["unchanged"],
            "max_relative_error": max(r["max_relative_error"] for r in reports),
            "meshes": [{k: (list(v) if isinstance(v, tuple) else v) for k, v in r.items()} for r in reports],
            "summary": (f"{totals['baked']:,} of {totals['submeshes']:,} submeshes baked, "
                        f"{totals['cache_hits']:,} cache hits, {totals['unchanged']:,} unchanged, "
                        f"worst decode error {max(r['max_relative_error'] for r in reports):.2e} of half-extent")}


def _mesh_counts(objects) -> dict:
    meshes = _meshes(objects)
    return {"vertices": sum(len(m.vertices) for m in meshes), "faces": sum(len(m.polygons) for m in meshes)}


def step_cleanup(bpy, objects, args, command) -> dict:
    """dedup / merge / pack-uv: the add-on's operator of that name, by id."""
    op_id, options = CLEANUP_OPERATORS[command]
    if not hasattr(bpy.types, "BOXMARCH_OT_" + op_id):
        raise MissingFeature(f"'{command}' needs the operator boxmarch.{op_id}, which this build of "
                             f"boxmarch does not have")
    operator = getattr(bpy.ops.boxmarch, op_id)
    known = operator.get_rna_type().properties.keys()
    kwargs = {}
    for option, prop in options.items():
        value = getattr(args, option, None)
        if value is None:
            continue
        if prop not in known:
            raise MissingFeature(f"boxmarch.{op_id} has no option '{prop}'")
        kwargs[prop] = value
    before = _mesh_counts(objects)
    _progress(f"{command}: {before['vertices']:,} vertices in {len(objects)} object(s)")
    start = time.perf_counter()
    try:
        result = operator(**kwargs)
    except RuntimeError as error:  # the operator's own ERROR report
        raise InputError(f"{command}: {str(error).strip().splitlines()[-1]}") from None
    seconds = time.perf_counter() - start
    if "FINISHED" not in result:
        raise InputError(f"{command}: boxmarch.{op_id} did nothing ({', '.join(sorted(result))})")
    after = _mesh_counts(objects)
    return {"step": command, "seconds": seconds, "options": kwargs, "before": before, "after": after,
            "summary": f"vertices {before['vertices']:,} -> {after['vertices']:,}, "
                       f"faces {before['faces']:,} -> {after['faces']:,}"}


def step_export(bpy, objects, args) -> dict:
    from .export import scene

    if not args.to:
        raise InputError("export needs --to PATH (the .fbx, .glb or .blend to write)")
    _progress(f"export: {args.preset} -> {args.to}")
    try:
        report = scene.export_objects(bpy.context, objects, args.preset, args.to, args.layout)
    except scene.ExportInputError as error:
        raise InputError(f"nothing exported: {error}") from None
    for warning in report["warnings"]:
        _progress(f"WARNING: {warning}")
    return {"step": "export", **report,
            "summary": f"{args.preset} ({report['layout']}) -> {report['path']}, transform error "
                       f"{report['transform_error']:.1e} of the offset reach; import settings: {report['import_settings']}"}


def _run_steps(args, steps) -> int:
    import bpy

    start = time.perf_counter()
    _check_outputs(None, args, steps)  # before opening: nothing is loaded for a bad path
    _open(bpy, args)
    _check_outputs(bpy, args, steps)  # the file Blender itself opened is an input too
    _check_cleanup_options(bpy, args, steps)
    hidden = [ob.name for ob in bpy.context.view_layer.objects if ob.hide_get()]
    objects = _objects(bpy, args)
    names = [ob.name for ob in objects]
    reports = []
    for step in steps:
        objects = [bpy.data.objects[name] for name in names]  # re-fetch: operators may rebuild data
        if step == "bake":
            reports.append(step_bake(bpy, objects, args))
        elif step == "export":
            reports.append(step_export(bpy, objects, args))
        else:
            reports.append(step_cleanup(bpy, objects, args, step))
    for name in hidden:
        bpy.data.objects[name].hide_set(True)
    out = _save_blend(bpy, args.out) if args.out else None
    total = time.perf_counter() - start
    rows = [[r["step"], f"{r['seconds']:.3f} s", r["summary"]] for r in reports]
    rows.append(["total", f"{total:.3f} s", f"wrote {out}" if out else "no --out: the .blend was not saved"])
    print(_table(["step", "time", "result"], rows))
    report = {"ok": True, "command": args.command, "blender": bpy.app.version_string,
              "file": bpy.data.filepath or None, "objects": names, "steps": reports, "out": out,
              "seconds": total}
    if args.json:
        _write_json(args.json, report)
    return 0


def cmd_bake(args):
    return _run_steps(args, ["bake"])


def cmd_cleanup(args):
    return _run_steps(args, [args.command])


def cmd_export(args):
    return _run_steps(args, ["export"])


def cmd_pipeline(args):
    steps = [s.strip() for s in args.steps.split(",") if s.strip()]
    unknown = [s for s in steps if s not in PIPELINE_STEPS]
    if unknown or not steps:
        raise InputError(f"--steps takes a comma-separated list of {', '.join(PIPELINE_STEPS)}; got {args.steps!r}")
    if "export" in steps and not args.to:
        raise InputError("the pipeline exports: give --to PATH")
    return _run_steps(args, steps)


# ---------------------------------------------------------------------------------------------
# demo

DEMO_IMAGE_SIZE = (640, 360)


def _demo_world(bpy, np, args):
    """The box world of the README: ``args.count`` boxes of varied sizes and rotations, 5% of them
    translated copies (the copy cache's case), 2% exact duplicates of others (for dedup) and 2%
    with one corner split into two vertices 1e-5 apart (for merge), plus chains of links laid
    along three curves with the instance-on-curve group. Returns (world object, chain object or
    None, expected duplicates, expected split corners)."""
    from . import mesh_io, scenes

    rng = np.random.default_rng(args.seed)
    duplicates = args.count // 50
    splits = args.count // 50
    unique = args.count - duplicates
    copies = unique // 20
    sizes = rng.uniform(0.05, 2.0, (unique, 3))
    rotations = scenes.random_rotations(unique, rng)
    sizes[-copies:] = sizes[:copies]
    rotations[-copies:] = rotations[:copies]
    centres = rng.uniform(-100, 100, (unique, 3))
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
    world = bpy.data.objects.new("BoxWorld", mesh_io.new_mesh("BoxWorld", positions, face_starts, face_sizes,
                                                               corner_verts))
    bpy.context.scene.collection.objects.link(world)

    chains = None
    if hasattr(bpy.types, "BOXMARCH_OT_add_instance_on_curve"):
        (link_positions, _e, link_starts, link_sizes, link_corners) = scenes.box_arrays(
            np.zeros((1, 3)), np.array([[0.3, 0.6, 0.1]]), np.eye(3)[None])
        link = bpy.data.objects.new("Link", mesh_io.new_mesh("Link", link_positions, link_starts, link_sizes,
                                                             link_corners))
        bpy.context.scene.collection.objects.link(link)
        converted = []
        for i in range(3):  # helices around the origin, where the camera looks
            t = np.linspace(0.0, 4.0 * np.pi, 64)
            curve_data = bpy.data.curves.new(f"Chain{i}", "CURVE")
            curve_data.dimensions = "3D"
            spline = curve_data.splines.new("POLY")
            spline.points.add(len(t) - 1)
            radius = 3.0 + 2.0 * i
            points = np.stack([radius * np.cos(t + i), radius * np.sin(t + i), 1.5 * t - 9.0, np.ones_like(t)], 1)
            spline.points.foreach_set("co", points.astype(np.float32).reshape(-1))
            curve = bpy.data.objects.new(f"Chain{i}", curve_data)
            bpy.context.scene.collection.objects.link(curve)
            for ob in bpy.context.scene.objects:
                ob.select_set(ob == curve)
            bpy.context.view_layer.objects.active = curve
            bpy.ops.boxmarch.add_instance_on_curve(instance=link.name, spacing=0.7, convert_to_mesh=True)
            converted.append(bpy.data.objects[f"Chain{i}"])
        bpy.data.objects.remove(link)
        for ob in bpy.context.scene.objects:
            ob.select_set(ob in converted)
        bpy.context.view_layer.objects.active = converted[0]
        bpy.ops.object.join()
        chains = bpy.context.view_layer.objects.active
        chains.name = chains.data.name = "Chains"
    return world, chains, duplicates, splits


def _select(bpy, objects):
    for ob in bpy.context.scene.objects:
        ob.select_set(ob in objects)
    bpy.context.view_layer.objects.active = objects[0]


def _bake_all(mesh_io, meshes, encoding, incremental):
    """Bake every mesh (as the bake command does); (seconds, prepared bakes, reports)."""
    settings = mesh_io.BakeSettings(encoding=encoding, incremental=incremental)
    t = time.perf_counter()
    prepared = [mesh_io.prepare_bake(mesh, settings) for mesh in meshes]
    reports = [p.write() for p in prepared]
    return time.perf_counter() - t, prepared, reports


def _glb_decode_error(np, path, objects, prepared):
    """Read ``path`` back (boxmarch.export.glb) and decode every vertex in glTF's frame with the
    shader's formula; worst distance to the baked centre of its submesh put in glTF's frame, over
    that submesh's largest half-extent."""
    from . import mesh_io
    from .export import glb, transforms

    preset = transforms.PRESETS["GLTF"]
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


def _demo_camera(bpy):
    data = bpy.data.cameras.new("DemoCamera")
    data.lens = 30.0
    camera = bpy.data.objects.new("DemoCamera", data)
    bpy.context.scene.collection.objects.link(camera)
    camera.location = (0.0, -24.0, 3.0)
    camera.rotation_euler = (math.radians(85.0), 0.0, 0.0)  # looks at the chains around the origin
    bpy.context.scene.camera = camera
    return camera


def _preview_picture(bpy, np, objects, sdfs, path, renderer="AUTO"):
    """Render the preview picture: the GPU raymarch preview when a GPU context can be made (or
    ``renderer`` is 'GPU'), else the CPU reference raymarcher (same decode, same SDFs). Returns
    the method used."""
    from . import core, preview
    from .preview import mesh_data

    scene = bpy.context.scene
    camera = _demo_camera(bpy)
    width, height = DEMO_IMAGE_SIZE
    for ob, sdf in zip(objects, sdfs):
        ob.boxmarch.sdf = sdf
        ob.boxmarch.preview = True
    rgba = None
    if renderer != "CPU":
        try:
            rgba, _depth = preview.render(scene, camera, width, height)
            method = "GPU raymarch preview"
        except (SystemError, RuntimeError) as error:  # no GPU context here
            if renderer == "GPU":
                raise
            _progress(f"preview: no GPU ({str(error).splitlines()[0]}), using the CPU reference raymarcher")
    if rgba is None:
        view, projection = preview.camera_matrices(scene, camera, width, height)
        depth = np.ones((height, width), np.float32)
        rgba = np.zeros((height, width, 4), np.float32)
        for ob, sdf in zip(objects, sdfs):
            baked = mesh_data.read_baked(ob.data)  # the boxes the GPU preview draws
            world = np.array(ob.matrix_world, np.float64)
            core.render_boxes(baked.origins, baked.box_quaternions, baked.box_half_extents,
                              projection @ view @ world, view @ world, width, height, sdf=sdf,
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
        _write_atomically(path, save)
    finally:
        bpy.data.images.remove(image)
    return method


def demo(args) -> int:
    """The README's main job, headless: build the box world (duplicates, split corners, chains
    along curves), run dedup, merge, bake (8-bit and float, then an incremental re-bake) and
    pack-uv, export demo.glb with the GLTF preset and decode it back in glTF's frame, render
    demo.png, save demo.blend, and print a table of timings and decode errors."""
    import bpy
    import numpy as np

    from . import mesh_io
    from .export import scene as export_scene

    if args.count < 100:
        raise InputError("--count must be at least 100")
    os.makedirs(args.out, exist_ok=True)
    rows = []
    start = time.perf_counter()
    _progress(f"building {args.count:,} boxes and the chains")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    _ensure_registered(bpy)
    world, chains, duplicates, splits = _demo_world(bpy, np, args)
    objects = [ob for ob in (world, chains) if ob is not None]
    meshes = [ob.data for ob in objects]
    links = len(chains.data.vertices) // 8 if chains else 0
    rows.append(["build scene", f"{time.perf_counter() - start:.3f} s",
                 f"{len(world.data.vertices):,} vertices; {links} chain links on 3 curves", ""])

    for command, option, expected in (("dedup", {"tolerance": 1e-4}, f"{duplicates} exact duplicates planted"),
                                      ("merge", {"distance": 1e-3}, f"{splits} split corners planted")):
        op_id = CLEANUP_OPERATORS[command][0]
        if not hasattr(bpy.types, "BOXMARCH_OT_" + op_id):
            rows.append([command, "-", f"skipped: boxmarch.{op_id} is not in this build", ""])
            continue
        _progress(command)
        _select(bpy, [world])
        before = len(world.data.vertices)
        t = time.perf_counter()
        getattr(bpy.ops.boxmarch, op_id)(**option)
        rows.append([command, f"{time.perf_counter() - t:.3f} s",
                     f"{before:,} -> {len(world.data.vertices):,} vertices", expected])

    for encoding in ("BYTE_COLOR", "FLOAT_COLOR"):
        _progress(f"baking ({encoding})")
        seconds, prepared, reports = _bake_all(mesh_io, meshes, encoding, incremental=False)
        rs = [p.result for p in prepared]
        rows.append([f"bake {encoding}", f"{seconds:.3f} s",
                     f"{sum(r.baked for r in rs):,} submeshes, {sum(r.cache_hits for r in rs):,} cache hits, "
                     f"{sum(r.degenerate for r in rs)} degenerate",
                     f"worst decode error {max(r.max_relative_error for r in rs):.2e} of half-extent "
                     f"(UV channels {reports[0]['uv_channels'][0]}, {reports[0]['uv_channels'][1]})"])
    float_bakes = prepared
    _progress("re-baking unchanged geometry")
    seconds, prepared, _ = _bake_all(mesh_io, meshes, "FLOAT_COLOR", incremental=True)
    rows.append(["re-bake (incremental)", f"{seconds:.3f} s",
                 f"{sum(p.result.unchanged for p in prepared):,} unchanged submeshes skipped", ""])

    if hasattr(bpy.types, "BOXMARCH_OT_pack_uv_by_z"):
        _progress("packing UVs by height")
        _select(bpy, objects)
        t = time.perf_counter()
        bpy.ops.boxmarch.pack_uv_by_z(uv_map="UVMap")
        rows.append(["pack-uv", f"{time.perf_counter() - t:.3f} s", "UVMap islands in rows by Z", ""])
    else:
        rows.append(["pack-uv", "-", "skipped: boxmarch.pack_uv_by_z is not in this build", ""])

    _progress("exporting demo.glb (GLTF preset)")
    glb_path = os.path.abspath(os.path.join(args.out, "demo.glb"))
    t = time.perf_counter()
    export_scene.export_objects(bpy.context, objects, "GLTF", glb_path)
    seconds = time.perf_counter() - t
    worst = _glb_decode_error(np, glb_path, objects, float_bakes)
    rows.append(["export demo.glb", f"{seconds:.3f} s", f"{os.path.getsize(glb_path) / 1e6:.1f} MB",
                 f"read back: worst decode error {worst:.2e} of half-extent in glTF's frame"])

    _progress("exporting for every engine")
    from .export.every_engine import export_every_engine
    for report in export_every_engine(bpy.context, objects, os.path.abspath(args.out), "demo"):
        lost = report["default_import_error"]
        files = [os.path.basename(p) for p in (report["path"], report["table"]) if p]
        rows.append([f"export {report['preset']}", f"{report['seconds']:.3f} s",
                     f"{' + '.join(files)}, layout {report['layout']}",
                     f"default import loses: {lost:.1e} of half-extent" if lost else "float32 in the engine"])

    png_path = os.path.abspath(os.path.join(args.out, "demo.png"))
    _progress("rendering demo.png")
    t = time.perf_counter()
    method = _preview_picture(bpy, np, objects, ["ROUNDED_BOX", "LINK"][:len(objects)], png_path, args.preview)
    rows.append(["preview demo.png", f"{time.perf_counter() - t:.3f} s",
                 f"{DEMO_IMAGE_SIZE[0]} x {DEMO_IMAGE_SIZE[1]}, {method}", ""])

    path = os.path.abspath(os.path.join(args.out, "demo.blend"))
    _save_blend(bpy, path)
    rows.append(["total", f"{time.perf_counter() - start:.3f} s", f"wrote {path}", ""])
    print(f"boxmarch demo: {args.count:,} boxes, Blender {bpy.app.version_string}")
    print(_table(["step", "time", "what", "accuracy"], rows))
    if args.json:
        _write_json(args.json, {"ok": True, "command": "demo", "count": args.count, "blend": path,
                                "glb": glb_path, "png": png_path, "preview": method,
                                "glb_max_relative_error": worst, "rows": rows, "blender": bpy.app.version_string})
    return 0


# ---------------------------------------------------------------------------------------------
# Argument parsing


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit code 2
        command = self.prog.split(" ", 1)[1:]  # "boxmarch bake" -> "bake: ..."; top level: the message
        raise InputError(f"{command[0]}: {message}" if command else message)


def _target_options(p, out_help="write the result as a new .blend (the input file is never changed)"):
    p.add_argument("blend", nargs="?", metavar="FILE.blend",
                   help="file to open (omit inside `blender FILE.blend --python-expr ...`)")
    p.add_argument("--objects", nargs="+", metavar="NAME", help="objects to work on (default: every mesh)")
    p.add_argument("--out", metavar="OUT.blend", help=out_help)
    p.add_argument("--json", metavar="REPORT.json", help="write a machine-readable report")


def _bake_options(p):
    p.add_argument("--origin", choices=("BOUNDS", "MEAN"), default="BOUNDS")
    p.add_argument("--angle-epsilon", type=float, default=0.1, help="radians (default 0.1)")
    p.add_argument("--encoding", choices=("FLOAT_COLOR", "BYTE_COLOR"), default="FLOAT_COLOR")
    p.add_argument("--domain", choices=("POINT", "CORNER"), default="POINT")
    p.add_argument("--axis-turn", type=int, default=0, choices=range(24), metavar="0..23")
    p.add_argument("--sort-axes-by-extent", action="store_true")
    p.add_argument("--no-cache", action="store_true", help="derive every frame (no copy cache)")
    p.add_argument("--full", action="store_true", help="re-bake unchanged submeshes too")


def _cleanup_options(p, command):
    if command in ("dedup", "pipeline"):
        p.add_argument("--tolerance", type=float, help="dedup: vertices this close count as the same")
    if command in ("merge", "pipeline"):
        p.add_argument("--distance", type=float, help="merge: merge distance within each submesh")
    if command in ("pack-uv", "pipeline"):
        p.add_argument("--padding", type=float)
        p.add_argument("--max-per-row", type=int)
        p.add_argument("--lock-overlapping", action="store_true", default=None)
        p.add_argument("--uv-map", help="UV map to pack (default: the operator's)")


def _export_options(p, required):
    from .export.layouts import LAYOUTS
    from .export.transforms import PRESETS

    p.add_argument("--preset", choices=sorted(PRESETS), default="GLTF")
    p.add_argument("--layout", choices=sorted(LAYOUTS), default=None,
                   help="channels to write (default: the preset's own, docs/ENGINES.md)")
    p.add_argument("--to", required=required, metavar="PATH", help="file to export (.fbx, .glb or .blend)")


def build_parser():
    parser = _Parser(prog="boxmarch", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p = commands.add_parser("bake", help="bake box frames")
    _target_options(p)
    _bake_options(p)
    p.set_defaults(run=cmd_bake)
    for command, text in (("dedup", "remove duplicate submeshes"),
                          ("merge", "merge by distance within each submesh"),
                          ("pack-uv", "pack UV islands by submesh height")):
        p = commands.add_parser(command, help=text)
        _target_options(p)
        _cleanup_options(p, command)
        p.set_defaults(run=cmd_cleanup)
    p = commands.add_parser("export", help="export baked meshes for an engine")
    _target_options(p)
    _export_options(p, required=True)
    p.set_defaults(run=cmd_export)
    p = commands.add_parser("pipeline", help="chain steps: --steps dedup,merge,bake,pack-uv,export")
    _target_options(p)
    p.add_argument("--steps", default="bake,export", help="comma-separated steps, run in this order")
    _bake_options(p)
    _cleanup_options(p, "pipeline")
    _export_options(p, required=False)
    p.set_defaults(run=cmd_pipeline)
    p = commands.add_parser("demo", help="build, bake, export and check a world of boxes")
    p.add_argument("--count", type=int, default=16000, help="number of boxes (default 16000)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="demo_out", help="folder for demo.blend and demo.glb (default ./demo_out)")
    p.add_argument("--preview", choices=("AUTO", "GPU", "CPU"), default="AUTO",
                   help="renderer of demo.png (AUTO: the GPU preview if a GPU context can be made)")
    p.add_argument("--json", metavar="REPORT.json")
    p.set_defaults(run=demo)
    return parser


def run(argv=None) -> int:
    """Run one command; returns the exit code (0, 2 bad input, 1 internal error)."""
    if argv is None:
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    args = None
    try:
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exit_:  # --help
            return 0 if not exit_.code else 2
        return args.run(args)
    except InputError as error:
        code, message = 2, f"boxmarch: error: {error}"
    except MissingFeature as error:
        code, message = 1, f"boxmarch: not available: {error}"
    except Exception as error:  # internal error: one line, exit 1
        code, message = 1, f"boxmarch: internal error: {error!r}"
    print(message, file=sys.stderr)
    if args is not None and getattr(args, "json", None):
        try:
            _write_json(args.json, {"ok": False, "command": args.command, "exit_code": code, "error": message})
        except Exception:
            pass  # the error line above is the report
    return code


def main(argv=None):
    """Entry point of both forms: exits the Python (or Blender) with the command's code."""
    code = run(argv)
    sys.stdout.flush()
    sys.stderr.flush()
    bpy = sys.modules.get("bpy")
    if bpy is not None and bpy.app.binary_path:
        # Inside the Blender program (the bpy module has no binary path) a SystemExit raised by
        # --python-expr is swallowed and Blender exits 0, so end the process with the code here.
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()

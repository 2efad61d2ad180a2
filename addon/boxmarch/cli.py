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
        if head not in (b"BLENDER",) and not head.startswith((b"\x1f\x8b", b"\x28\xb5\x2f\xfd")):
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
    of the scene; selects exactly them and makes the first active."""
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
    totals = {key: sum(r[key] for r in reports)
              for key in ("submeshes", "baked", "cache_hits", "unchanged", "degenerate")}
    return {"step": "bake", "seconds": seconds, **totals,
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
        report = scene.export_objects(bpy.context, objects, args.preset, args.to)
    except scene.ExportInputError as error:
        raise InputError(f"nothing exported: {error}") from None
    for warning in report["warnings"]:
        _progress(f"warning: {warning}")
    return {"step": "export", **report,
            "summary": f"{args.preset} -> {report['path']}, transform error {report['transform_error']:.1e} of the offset reach"}


def _run_steps(args, steps) -> int:
    import bpy

    start = time.perf_counter()
    _open(bpy, args)
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


def demo(args) -> int:
    """Build a world of boxes (varied sizes and rotations, some exact translated copies), bake it
    headless through the add-on's operator in float and 8-bit colour, decode the stored data and
    print timings and decode errors; write the baked scene to OUT/demo.blend and the glTF preset's
    export to OUT/demo.glb, read back and decoded in glTF's frame."""
    import bpy
    import numpy as np

    from . import core, mesh_io, scenes
    from .export import glb, scene as export_scene, transforms

    if args.count < 1:
        raise InputError("--count must be at least 1")
    os.makedirs(args.out, exist_ok=True)
    rows = []
    start = time.perf_counter()
    _progress(f"building {args.count:,} boxes")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    _ensure_registered(bpy)
    rng = np.random.default_rng(args.seed)
    copies = args.count // 20  # 5% exact translated copies of the first boxes: the copy cache's case
    sizes = rng.uniform(0.05, 2.0, (args.count, 3))
    rotations = scenes.random_rotations(args.count, rng)
    sizes[-copies:] = sizes[:copies]
    rotations[-copies:] = rotations[:copies]
    centres = rng.uniform(-100, 100, (args.count, 3))
    positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, sizes, rotations)
    mesh = mesh_io.new_mesh("BoxWorld", positions, face_starts, face_sizes, corner_verts)
    ob = bpy.data.objects.new("BoxWorld", mesh)
    bpy.context.scene.collection.objects.link(ob)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    rows.append(["build scene", f"{time.perf_counter() - start:.3f} s", f"{len(mesh.vertices):,} vertices", ""])

    for encoding in ("BYTE_COLOR", "FLOAT_COLOR"):
        _progress(f"baking ({encoding})")
        settings = mesh_io.BakeSettings(encoding=encoding, incremental=False)
        t = time.perf_counter()
        prepared = mesh_io.prepare_bake(mesh, settings)
        report = prepared.write()
        seconds = time.perf_counter() - t
        r = prepared.result
        baked_origins = r.origins  # float64 centre of each stored (float32) box, in Blender's frame
        rows.append([f"bake {encoding}", f"{seconds:.3f} s",
                     f"{r.baked:,} submeshes, {r.cache_hits:,} cache hits, {r.degenerate} degenerate",
                     f"worst decode error {r.max_relative_error:.2e} of half-extent "
                     f"(UV channels {report['uv_channels'][0]}, {report['uv_channels'][1]})"])
    _progress("re-baking unchanged geometry")
    t = time.perf_counter()
    prepared = mesh_io.prepare_bake(mesh, mesh_io.BakeSettings(encoding="FLOAT_COLOR"))
    prepared.write()
    rows.append(["re-bake (incremental)", f"{time.perf_counter() - t:.3f} s",
                 f"{prepared.result.unchanged:,} unchanged submeshes skipped", ""])

    _progress("exporting demo.glb (GLTF preset)")
    glb_path = os.path.abspath(os.path.join(args.out, "demo.glb"))
    t = time.perf_counter()
    export_scene.export_objects(bpy.context, [ob], "GLTF", glb_path)
    seconds = time.perf_counter() - t
    # Read the file back, decode every vertex in glTF's frame (the shader's formula) and compare
    # with the baked centres put in glTF's frame (the exact centres differ from those of the
    # float32-rounded boxes by up to half a float32 step of the coordinates).
    gltf, binary = glb.read(glb_path)
    worst = 0.0
    preset = transforms.PRESETS["GLTF"]
    target_centres = transforms.target_positions(baked_origins, preset)
    ours = transforms.target_positions(positions, preset).astype(np.float32)  # exact: a signed permutation
    half = sizes.max(axis=1) / 2
    for primitive in gltf["meshes"][0]["primitives"]:
        a = {k: glb.accessor_array(gltf, binary, i).astype(np.float64) for k, i in primitive["attributes"].items()}
        q = np.concatenate([a["TEXCOORD_1"], a["TEXCOORD_2"]], axis=1)
        origin = a["POSITION"] + core.rotate_vector(core.decode_offsets(a["COLOR_0"]), q)
        # The box of each file vertex: the Blender vertex at exactly that position (sort-based match).
        _, group = np.unique(np.concatenate([ours, a["POSITION"].astype(np.float32)]), axis=0, return_inverse=True)
        group = group.reshape(-1)
        vertex_of_group = np.full(group.max() + 1, -1)
        vertex_of_group[group[:len(ours)]] = np.arange(len(ours))
        box = vertex_of_group[group[len(ours):]] // 8
        if (box < 0).any():
            raise RuntimeError("demo.glb holds a vertex the scene does not have")
        worst = max(worst, float((np.linalg.norm(origin - target_centres[box], axis=1) / half[box]).max()))
    rows.append(["export demo.glb", f"{seconds:.3f} s", f"{os.path.getsize(glb_path) / 1e6:.1f} MB",
                 f"read back: worst decode error {worst:.2e} of half-extent in glTF's frame"])

    path = os.path.abspath(os.path.join(args.out, "demo.blend"))
    _save_blend(bpy, path)
    rows.append(["total", f"{time.perf_counter() - start:.3f} s", f"wrote {path}", ""])
    print(f"boxmarch demo: {args.count:,} boxes, Blender {bpy.app.version_string}")
    print(_table(["step", "time", "what", "accuracy"], rows))
    if args.json:
        _write_json(args.json, {"ok": True, "command": "demo", "count": args.count, "blend": path,
                                "glb": glb_path, "glb_max_relative_error": worst,
                                "rows": rows, "blender": bpy.app.version_string})
    return 0


# ---------------------------------------------------------------------------------------------
# Argument parsing


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit code 2
        raise InputError(f"{self.prog}: {message}")


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
    from .export.transforms import PRESETS

    p.add_argument("--preset", choices=sorted(PRESETS), default="GLTF")
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

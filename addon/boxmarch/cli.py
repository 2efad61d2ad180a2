"""Command line of boxmarch: the add-on's work from scripts and pipelines.

Two forms run the same commands:

    python -m boxmarch COMMAND [FILE.blend] [options]                     (a Python with bpy)
    blender --background FILE.blend --python-expr "import boxmarch.cli; boxmarch.cli.main()" -- COMMAND [options]

Commands: bake, dedup, merge, pack-uv, export, pipeline (chains them), demo. They work on the
objects named with --objects, or on every mesh object of the file. --out writes the result as a
new .blend, --json a machine-readable report; both appear only complete (written under a
temporary name, then renamed). Progress goes to stderr, the result table to stdout (Blender's
own prints are held back), at most TABLE_WIDTH characters wide. Exit codes: 0 success, 2 bad
arguments or input (one line saying why; a command given no .blend is one), 3 no bpy module in
this Python or boxmarch's native module not built (the line says what to install or build), 128 +
the signal's number when a signal stopped it (130 for Ctrl-C, 143 for SIGTERM), 1 internal
error. docs/CLI.md has the reference.

This module only parses, checks and reports: every step runs the same job function as the
add-on's operator (bake_job.bake_meshes, tool_jobs.run_tool, export.scene.export_objects).
"""
from __future__ import annotations

import json
import math
import os
import re
import signal
import sys
import time

from . import NativeModuleMissing, ensure_registered
from .cli_args import InputError, build_parser, check_outputs, run_outputs
from .formats import files

PIPELINE_STEPS = ("dedup", "merge", "bake", "pack-uv", "export")
# The tool each cleanup command runs (a tool_jobs class name), its operator (whose properties
# give the ranges an option must lie in; boxmarch.ID) and {command-line option: tool option}.
CLEANUP_TOOLS = {
    "dedup": ("DeleteDuplicates", "dedup_submeshes", {"tolerance": "tolerance"}),
    "merge": ("MergeByDistance", "merge_by_distance_submeshes", {"distance": "distance"}),
    "pack-uv": ("PackUvByZ", "pack_uv_by_z", {"padding": "padding", "max_per_row": "max_per_row",
                                                         "lock_overlapping": "lock_overlapping", "uv_map": "uv_map"}),
}


TABLE_WIDTH = 100  # characters: the result table fits a terminal; longer cells wrap within their column
NARROWEST_COLUMN = 12
EXIT_MISSING_MODULE = 3  # no bpy module in this Python, or boxmarch's native module not built
NO_BPY_MESSAGE = ("boxmarch: error: this Python has no bpy module: install Blender as a Python module "
                  "(pip install bpy==5.0.*, on Python 3.11), or run the command in the Blender program "
                  "(blender --background FILE.blend --python-expr \"import boxmarch.cli; boxmarch.cli.main()\" "
                  "-- COMMAND ...; docs/CLI.md)")


def _progress(message: str) -> None:
    print(f"[boxmarch] {message}", file=sys.stderr, flush=True)


def _pieces(word: str) -> list:
    """A word cut after each '/' it holds (a path's components), the places a long word may break."""
    return [piece for piece in re.split(r"(?<=/)", word) if piece]


def _wrap(cell: str, width: int) -> list:
    """The cell's lines, each at most ``width`` wide, broken between words, a word wider than
    the line after one of its '/' and, only where a piece is still too wide, every ``width``
    characters (textwrap cuts a long word anywhere: 'e | ngines/unreal')."""
    lines = []
    for word in cell.split():
        pieces = [word] if len(word) <= width else [
            piece[i:i + width] for piece in _pieces(word) for i in range(0, len(piece), width)]
        for k, piece in enumerate(pieces):
            joined = (lines[-1] + (" " if k == 0 else "") + piece) if lines else piece
            if lines and len(joined) <= width:
                lines[-1] = joined
            else:
                lines.append(piece)
    return lines or [""]


def format_table(headers, rows, width=TABLE_WIDTH) -> str:
    """A Markdown-like table at most ``width`` characters wide: the widest columns are narrowed,
    first not below their longest word-or-path-component (NARROWEST_COLUMN at least), so their
    cells wrap between words or after a path's '/', then, where that cannot fit, down to
    NARROWEST_COLUMN; cells wrap onto continuation lines."""
    head, *body = [[str(cell) for cell in row] for row in [headers, *rows]]
    widths = [max(len(row[i]) for row in [head, *body]) for i in range(len(head))]
    pieces = [max([len(p) for row in [head, *body] for word in row[i].split() for p in _pieces(word)], default=0)
              for i in range(len(head))]
    for floors in ([max(NARROWEST_COLUMN, p) for p in pieces], [NARROWEST_COLUMN] * len(widths)):
        while sum(widths) + 3 * len(widths) + 1 > width and any(w > f for w, f in zip(widths, floors)):
            widest = max((i for i, w in enumerate(widths) if w > floors[i]), key=lambda i: widths[i])
            widths[widest] -= 1

    def lines(row):
        cells = [_wrap(cell, w) for cell, w in zip(row, widths)]
        return ["| " + " | ".join((cell[k] if k < len(cell) else "").ljust(w) for cell, w in zip(cells, widths)) + " |"
                for k in range(max(map(len, cells)))]
    rule = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    return "\n".join([*lines(head), rule, *(line for row in body for line in lines(row))])


def write_json(path: str, report: dict) -> None:
    """Writes ``report`` to ``path`` as strict JSON (NaN and infinities refused), atomically."""
    def write(temp):
        with open(temp, "w") as f:
            json.dump(report, f, indent=2, default=float, allow_nan=False)
    files.write_atomically(path, write)


def _accept_outputs(args, outputs, inputs, made_folders=()) -> None:
    """Check every output (cli_args.check_outputs); once they pass, a failure report may go to
    --json (a refused --json is never written, not even with the error)."""
    check_outputs(outputs, inputs, made_folders)
    args.failure_report = getattr(args, "json", None)


def _check_cleanup_options(bpy, args, steps) -> None:
    """Cleanup options outside what the operator accepts are refused (the operator would clamp
    them silently, and the report would record the unclamped value); the operator's properties
    are the one statement of those ranges."""
    for command in steps:
        if command not in CLEANUP_TOOLS:
            continue
        _tool, operator, options = CLEANUP_TOOLS[command]
        props = getattr(bpy.ops.boxmarch, operator).get_rna_type().properties
        for option, prop in options.items():
            value = getattr(args, option, None)
            if value is None or prop not in props or props[prop].type not in ("FLOAT", "INT"):
                continue
            lo, hi = props[prop].hard_min, props[prop].hard_max
            if not (math.isfinite(value) and lo <= value <= hi):
                raise InputError(f"--{option.replace('_', '-')} must be a finite number in [{lo:g}, {hi:g}], "
                                 f"got {value!r}")


# ---------------------------------------------------------------------------------------------
# Scene set-up shared by the commands


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
    ensure_registered()  # relative import: installed as an extension the package is bl_ext.*.boxmarch


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
    from . import edit_mode

    for ob in objects:
        ob.hide_set(False)
    edit_mode.select_only(bpy.context.view_layer, objects)
    return objects


# ---------------------------------------------------------------------------------------------
# Steps: each runs one job on the objects and returns a report dict


def step_bake(objects, args) -> dict:
    from . import bake_job, mesh_io

    settings = mesh_io.BakeSettings(
        angle_epsilon=args.angle_epsilon, origin=args.origin, encoding=args.encoding, domain=args.domain,
        axis_turn=args.axis_turn, sort_axes_by_extent=args.sort_axes_by_extent, use_cache=not args.no_cache,
        incremental=not args.full, hierarchy=args.parents, random_seed=args.random_seed)
    meshes = [ob.data for ob in mesh_io.one_object_per_mesh(objects)]
    start = time.perf_counter()
    try:
        prepared = bake_job.bake_meshes(meshes, settings, progress=lambda _step, _steps, what: (
            _progress(f"bake: {what}") if what.startswith("computing") else None))
    except mesh_io.BakeInputError as error:
        raise InputError(f"nothing baked: {error}") from None
    seconds = time.perf_counter() - start
    reports = [bake.report for bake in prepared]
    warnings = mesh_io.modifier_warnings(objects) + bake_job.not_box_warnings(reports)
    for warning in warnings:
        _progress(f"WARNING: {warning}")
    totals = bake_job.report_totals(reports)
    del totals["not_selected"]  # the command line bakes whole meshes
    return {"step": "bake", "seconds": seconds, **totals, "warnings": warnings, "skipped": totals["unchanged"],
            "meshes": [{k: (list(v) if isinstance(v, tuple) else v) for k, v in r.items()} for r in reports],
            "summary": (f"{totals['baked']:,} of {totals['submeshes']:,} submeshes baked, "
                        f"{totals['cache_hits']:,} cache hits, {totals['unchanged']:,} unchanged, "
                        f"worst decode error {totals['max_relative_error']:.2e} of half-extent")}


def _mesh_counts(objects) -> dict:
    from . import mesh_io

    meshes = [ob.data for ob in mesh_io.one_object_per_mesh(objects)]
    return {"vertices": sum(len(m.vertices) for m in meshes), "faces": sum(len(m.polygons) for m in meshes)}


def step_cleanup(objects, args, command) -> dict:
    """dedup / merge / pack-uv: the tool job the operator of that name runs."""
    import bpy

    from . import mesh_io, tool_jobs

    tool_name, _operator, options = CLEANUP_TOOLS[command]
    kwargs = {tool_option: getattr(args, option) for option, tool_option in options.items()
              if getattr(args, option, None) is not None}
    tool = getattr(tool_jobs, tool_name)(**kwargs)
    before = _mesh_counts(objects)
    _progress(f"{command}: {before['vertices']:,} vertices in {len(objects)} object(s)")
    start = time.perf_counter()
    try:
        tool_jobs.run_tool(bpy.context, tool, mesh_io.one_object_per_mesh(objects))
    except ValueError as error:  # ToolInputError, or the core refusing the input
        raise InputError(f"{command}: Nothing changed: {error}") from None
    seconds = time.perf_counter() - start
    after = _mesh_counts(objects)
    return {"step": command, "seconds": seconds, "options": kwargs, "before": before, "after": after,
            "summary": f"vertices {before['vertices']:,} -> {after['vertices']:,}, "
                       f"faces {before['faces']:,} -> {after['faces']:,}"}


def step_export(objects, args) -> dict:
    import bpy

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
                       f"{report['transform_error']:.1e} of the offset reach; import settings: "
                       f"{scene.import_note(report)}"}


def _run_step(step, objects, args) -> dict:
    if step == "bake":
        return step_bake(objects, args)
    if step == "export":
        return step_export(objects, args)
    return step_cleanup(objects, args, step)


def _run_steps(args, steps) -> int:
    import bpy

    from .blend_file import save_blend_copy

    start = time.perf_counter()
    if not getattr(args, "blend", None) and not bpy.data.filepath:  # else it would work on Blender's startup scene
        raise InputError(f"{args.command}: no .blend file to work on: give FILE.blend (boxmarch {args.command} "
                         "FILE.blend ...), or open it in the Blender program (blender --background FILE.blend ...)")
    # Before opening, so that nothing is loaded for a bad path; the file Blender itself opened
    # (the Blender form) is an input too.
    _accept_outputs(args, run_outputs(args, steps), [getattr(args, "blend", None), bpy.data.filepath])
    with _blender_stdout_held_back():
        _open(bpy, args)
        _check_cleanup_options(bpy, args, steps)
        hidden = [ob.name for ob in bpy.context.view_layer.objects if ob.hide_get()]
        names = [ob.name for ob in _objects(bpy, args)]
        reports = []
        for step in steps:
            objects = [bpy.data.objects[name] for name in names]  # re-fetch: jobs may rebuild data
            reports.append(_run_step(step, objects, args))
        for name in hidden:
            bpy.data.objects[name].hide_set(True)
        out = save_blend_copy(args.out) if args.out else None
    total = time.perf_counter() - start
    rows = [[r["step"], f"{r['seconds']:.3f} s", r["summary"]] for r in reports]
    rows.append(["total", f"{total:.3f} s", f"wrote {out}" if out else "no --out: the .blend was not saved"])
    print(format_table(["step", "time", "result"], rows))
    report = {"ok": True, "command": args.command, "blender": bpy.app.version_string,
              "file": bpy.data.filepath or None, "objects": names, "steps": reports, "out": out,
              "seconds": total}
    if args.json:
        write_json(args.json, report)
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


def cmd_demo(args) -> int:
    import bpy

    from . import demo

    if not 100 <= args.count <= demo.MAX_COUNT:
        raise InputError(f"--count must be in 100..{demo.MAX_COUNT:,}, got {args.count:,}")
    if args.seed < 0:
        raise InputError(f"--seed must be 0 or more, got {args.seed}")
    folder = os.path.abspath(args.out)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise InputError(f"--out '{args.out}' is a file: the demo writes its files into a folder")
    # The demo starts a new scene: a file Blender opened (the Blender form) is an input it must not replace.
    _accept_outputs(args, [("--out", path) for path in demo.demo_outputs(folder)] +
                    ([("--json", args.json)] if args.json else []), [bpy.data.filepath], made_folders=[folder])
    with _blender_stdout_held_back():
        rows, report = demo.run_demo(args.count, args.seed, folder, args.preview, _progress)
    print(f"boxmarch demo: {args.count:,} boxes, Blender {bpy.app.version_string}")
    print(format_table(["step", "time", "what", "accuracy"], rows))
    if args.json:
        write_json(args.json, report)
    return 0


def _blender_stdout_held_back():
    """Blender's own prints (its exporters and its save name the temporary files; operator
    reports) stay off stdout, which holds the result table; warnings and errors go to stderr."""
    from . import blender_output

    return blender_output.stdout_held_back(lambda line: _progress(f"Blender: {line}"))


def _interrupted_code(interrupts) -> tuple[int, str]:
    """(exit code, message) of a run stopped by the signal ``interrupts[0]`` (Ctrl-C where none
    was recorded: a KeyboardInterrupt outside the handler): 128 + the signal's number, as a
    shell reports a process the signal ended."""
    signum = interrupts[0] if interrupts else signal.SIGINT
    return 128 + signum, (f"boxmarch: interrupted: stopped by {signal.Signals(signum).name}, each output is either "
                          "complete or not written (no partial file is left)")


def run(argv=None) -> int:
    """Run one command; returns the exit code (0; 2 bad input; 3 no bpy or native module; 128 + the
    signal's number when stopped by one, 130 for Ctrl-C; 1 internal error). ``argv`` None: the
    process's arguments; inside the Blender program those after its first ``--`` (Blender's own
    come before it)."""
    if argv is None:
        argv = sys.argv[1:]
        if _in_blender_program():
            argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args, interrupts = None, []
    try:
        with files.interrupts_recorded(interrupts):
            try:
                runners = {"bake": cmd_bake, "dedup": cmd_cleanup, "merge": cmd_cleanup, "pack-uv": cmd_cleanup,
                           "export": cmd_export, "pipeline": cmd_pipeline, "demo": cmd_demo}
                args = build_parser(__doc__.splitlines()[0], runners, _version()).parse_args(argv)
            except SystemExit as exit_:  # --help, --version
                return 0 if not exit_.code else 2
            return args.run(args)
    except (Exception, KeyboardInterrupt) as error:
        if interrupts or isinstance(error, KeyboardInterrupt):
            code, message = _interrupted_code(interrupts)
        elif isinstance(error, InputError):
            code, message = 2, f"boxmarch: error: {error}"
        elif isinstance(error, ModuleNotFoundError) and error.name == "bpy":
            code, message = EXIT_MISSING_MODULE, NO_BPY_MESSAGE
        elif isinstance(error, NativeModuleMissing):
            code, message = EXIT_MISSING_MODULE, f"boxmarch: error: {error}"
        else:  # internal error: one line, exit 1
            from .blender_output import one_line

            code, message = 1, f"boxmarch: internal error: {one_line(error)}"
    print(message, file=sys.stderr)
    report_path = getattr(args, "failure_report", None)  # only a --json the output checks accepted
    if report_path:
        try:
            write_json(report_path, {"ok": False, "command": args.command, "exit_code": code, "error": message})
        except Exception:
            pass  # the error line above is the report
    return code


def _version() -> str:
    """boxmarch's version (the add-on's bl_info), and Blender's where bpy is already loaded."""
    from . import bl_info

    text = "boxmarch " + ".".join(map(str, bl_info["version"]))
    bpy = sys.modules.get("bpy")
    return text + (f" (Blender {bpy.app.version_string})" if bpy is not None else "")


def _in_blender_program() -> bool:
    """Running inside the Blender program (the bpy module has no binary path)."""
    bpy = sys.modules.get("bpy")
    return bpy is not None and bool(bpy.app.binary_path)


def bpy_module_crashes_at_exit() -> bool:
    """The bpy module in use is 4.2 or 4.5 (PyPI), which segfault at interpreter exit once an
    add-on registered classes (docs/PLATFORMS.md): a process must leave with os._exit."""
    bpy = sys.modules.get("bpy")
    return bpy is not None and (4, 2, 0) <= bpy.app.version < (5, 0, 0)


def main(argv=None):
    """Entry point of both forms: exits the Python (or Blender) with the command's code."""
    code = run(argv)
    sys.stdout.flush()
    sys.stderr.flush()
    if _in_blender_program() or bpy_module_crashes_at_exit():
        # Inside the Blender program a SystemExit raised by --python-expr is swallowed and Blender
        # exits 0; the bpy modules 4.2 and 4.5 crash at interpreter exit. Either way, end the
        # process with the code here.
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()

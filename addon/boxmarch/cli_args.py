"""The command line's arguments: the parser of every command (boxmarch.cli runs them)."""
from __future__ import annotations

import argparse
import os

from .formats import files


class InputError(Exception):
    """Bad arguments or input: exit code 2 with this one-line message."""


class _DefaultsShown(argparse.HelpFormatter):
    """--help gives each option's default after its help, where it has one (flags and options
    without a value default have none) and the help does not already say it."""

    def _get_help_string(self, action):
        text = action.help or ""
        has_default = not any(action.default is none for none in (None, False, argparse.SUPPRESS))  # 0 is one
        if action.option_strings and has_default and "default" not in text:
            text += " (default: %(default)s)"
        return text


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _DefaultsShown)
        super().__init__(*args, **kwargs)

    def error(self, message):  # one line, exit code 2
        command = self.prog.split(" ", 1)[1:]  # "boxmarch bake" -> "bake: ..."; top level: the message
        raise InputError(f"{command[0]}: {message}" if command else message)


def _angle_epsilon(text):
    """--angle-epsilon as a float in core.ANGLE_EPSILON_RANGE (the bake operator's limits and the
    core's check), so the command line refuses what the core would refuse before any file opens."""
    from . import core

    lo, hi = core.ANGLE_EPSILON_RANGE
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid float value: {text!r}") from None
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"must be in [{lo:g}, {hi:.7g}] radians, got {text}")
    return value


def _random_seed(text):
    """--random-seed as an int in 0..core.RANDOM_SEED_MAX (the bake operator's Random Seed range)."""
    from . import core

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid int value: {text!r}") from None
    if not 0 <= value <= core.RANDOM_SEED_MAX:
        raise argparse.ArgumentTypeError(f"must be in 0..{core.RANDOM_SEED_MAX}, got {text}")
    return value


def _target_options(p, out_help="write the result as a new .blend (the input file is never changed)"):
    p.add_argument("blend", nargs="?", metavar="FILE.blend",
                   help="file to open (omit inside `blender FILE.blend --python-expr ...`)")
    p.add_argument("--objects", nargs="+", metavar="NAME", help="objects to work on (default: every mesh)")
    p.add_argument("--out", metavar="OUT.blend", help=out_help)
    p.add_argument("--json", metavar="REPORT.json", help="write a machine-readable report")


def _bake_options(p):
    # core here, not at the top: a checkout whose native module is not built then reaches
    # cli.run, which says how to build it in one line, instead of a traceback at import.
    from . import core

    p.add_argument("--origin", choices=core.ORIGIN_MODES, default=core.ORIGIN_MODES[0],
                   help="each box's origin: BOUNDS, the centre of its bounds in its own frame; MEAN, its vertices' mean")
    lo, hi = core.ANGLE_EPSILON_RANGE
    p.add_argument("--angle-epsilon", type=_angle_epsilon, default=core.ANGLE_EPSILON_DEFAULT,
                   help=f"radians, {lo:g}..{hi:.7g}: the second axis comes from the largest face at least this far "
                        "from the first axis's plane")
    p.add_argument("--encoding", choices=core.ENCODINGS, default=core.ENCODINGS[0],
                   help="the offset colour: FLOAT_COLOR (exact) or BYTE_COLOR (8-bit)")
    p.add_argument("--domain", choices=("POINT", "CORNER"), default="POINT",
                   help="one offset colour per vertex (POINT) or per face corner")
    p.add_argument("--axis-turn", type=int, default=0, choices=range(24), metavar="0..23",
                   help="turn the derived frame by one of the 24 axis-aligned rotations (offsets follow)")
    p.add_argument("--sort-axes-by-extent", action="store_true",
                   help="local X along each box's longest side, Z along its shortest, before the turn")
    p.add_argument("--no-cache", action="store_true", help="derive every frame (no copy cache)")
    p.add_argument("--full", action="store_true", help="re-bake unchanged submeshes too")
    p.add_argument("--parents", choices=core.HIERARCHY_RULES, default=core.HIERARCHY_RULES[0],
                   help="each box's parent: ATTRIBUTE (boxmarch_parent), CONTAINMENT, CHAIN or BONES "
                        "(the box of its bone's parent bone)")
    p.add_argument("--random-seed", type=_random_seed, default=0,
                   help=f"seed of each box's random value (0..{core.RANDOM_SEED_MAX})")


def _cleanup_options(p, command):
    from . import core_tools

    if command in ("dedup", "pipeline"):
        p.add_argument("--tolerance", type=float, default=core_tools.DUPLICATE_TOLERANCE,
                       help="dedup: vertices this close count as the same")
    if command in ("merge", "pipeline"):
        p.add_argument("--distance", type=float, default=core_tools.MERGE_DISTANCE,
                       help="merge: merge distance within each submesh")
    if command in ("pack-uv", "pipeline"):
        p.add_argument("--padding", type=float, default=core_tools.PACK_UV_PADDING,
                       help="pack-uv: UV space between islands and around the square")
        p.add_argument("--max-per-row", type=int, default=0, help="pack-uv: most islands in one row (0: as many as fit)")
        p.add_argument("--lock-overlapping", action="store_true", help="pack-uv: islands whose UV bounds overlap "
                                                                       "move together")
        p.add_argument("--uv-map", help="pack-uv: the UV map to pack (default: each mesh's active UV map)")


def _export_options(p, required):
    from .formats.layouts import LAYOUTS
    from .formats.presets import PRESETS

    p.add_argument("--preset", choices=sorted(PRESETS), default="GLTF", help="the engine's export (docs/ENGINES.md)")
    p.add_argument("--layout", choices=sorted(LAYOUTS), default=None,
                   help="channels to write (default: the preset's own, docs/ENGINES.md)")
    p.add_argument("--to", required=required, metavar="PATH", help="file to export (.fbx, .glb or .blend)")


def build_parser(description: str, runners: dict, version: str):
    """The parser of every command; ``runners`` = {command: the function that runs it}, set as
    the parsed arguments' ``run``; ``version``: what --version prints."""
    parser = _Parser(prog="boxmarch", description=description)
    parser.add_argument("--version", action="version", version=version)
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p = commands.add_parser("bake", help="bake box frames")
    _target_options(p)
    _bake_options(p)
    p.set_defaults(run=runners["bake"])
    for command, text in (("dedup", "remove duplicate submeshes"),
                          ("merge", "merge by distance within each submesh"),
                          ("pack-uv", "pack UV islands by submesh height")):
        p = commands.add_parser(command, help=text)
        _target_options(p)
        _cleanup_options(p, command)
        p.set_defaults(run=runners[command])
    p = commands.add_parser("export", help="export baked meshes for an engine")
    _target_options(p)
    _export_options(p, required=True)
    p.set_defaults(run=runners["export"])
    p = commands.add_parser("pipeline", help="chain steps: --steps dedup,merge,bake,pack-uv,export")
    _target_options(p)
    p.add_argument("--steps", default="bake,export", help="comma-separated steps, run in this order")
    _bake_options(p)
    _cleanup_options(p, "pipeline")
    _export_options(p, required=False)
    p.set_defaults(run=runners["pipeline"])
    p = commands.add_parser("demo", help="build, bake, export and check a world of boxes")
    p.add_argument("--count", type=int, default=16000, help="number of boxes, 100..1,000,000")
    p.add_argument("--seed", type=int, default=1, help="seed of the world's random boxes (0 or more)")
    p.add_argument("--out", default="demo_out", help="folder for demo.blend, demo.glb and the rest, made if missing")
    p.add_argument("--preview", choices=("AUTO", "GPU", "CPU"), default="AUTO",
                   help="renderer of demo.png (AUTO: the GPU preview if a GPU context can be made)")
    p.add_argument("--json", metavar="REPORT.json", help="write a machine-readable report")
    p.set_defaults(run=runners["demo"])
    return parser


# ---------------------------------------------------------------------------------------------
# Output paths: every check runs before anything is written


def run_outputs(args, steps) -> list:
    """[(option, path)] of every file a bake/cleanup/export/pipeline run writes: --out, each file
    the export writes (export.outputs_of: the sidecar, box table and Godot 3 import settings beside
    it too), --json.
    Refuses an --out that is not a .blend and a --to without the preset's extension."""
    outputs = []
    if getattr(args, "out", None):
        if not args.out.lower().endswith(".blend"):
            raise InputError(f"--out must name a .blend file, got '{args.out}'")
        outputs.append(("--out", args.out))
    if "export" in steps and getattr(args, "to", None):
        from .export import outputs_of, path_problem

        problem = path_problem(args.to, args.preset)
        if problem:
            raise InputError(f"--to: {problem}")
        outputs += [("--to" if path == args.to else "the export beside --to", path)
                    for path in outputs_of(args.to, args.preset, args.layout)]
    if getattr(args, "json", None):
        outputs.append(("--json", args.json))
    return outputs


def _writable_folder(option, folder, made_folders) -> None:
    """``folder`` exists and can be written, or is one the command makes (its nearest existing
    parent then must be a writable folder)."""
    if folder in made_folders:
        while not os.path.exists(folder):
            folder = os.path.dirname(folder)
        if not os.path.isdir(folder):
            raise InputError(f"{option}: '{folder}' is a file, not a folder")
    elif not os.path.isdir(folder):
        raise InputError(f"{option}: folder '{folder}' does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"{option}: cannot write into '{folder}' (permission denied)")


def check_outputs(outputs, inputs, made_folders=()) -> None:
    """Every check on the output paths ``outputs`` [(option, path)], run before anything is
    written (docs/CLI.md): each folder exists (or is in ``made_folders``) and is writable, no
    output is a folder, one of ``inputs`` (files never written) or another output; of an output
    that is a symbolic link, these hold for the file it names (files.written_path)."""
    inputs = [os.path.realpath(p) for p in inputs if p]
    made_folders = {os.path.realpath(f) for f in made_folders}
    seen = {}
    for option, path in outputs:
        name_bytes = len(os.path.basename(os.path.abspath(path)).encode())
        if name_bytes > files.NAME_MAX:
            raise InputError(f"{option}: the name '{os.path.basename(os.path.abspath(path))}' is {name_bytes} bytes, "
                             f"longer than the {files.NAME_MAX} bytes a file name may have")
        try:
            full = files.written_path(path)  # a symbolic link is written through: its target is the output
        except OSError as error:
            raise InputError(f"{option}: '{path}': {error.strerror}") from None
        _writable_folder(option, os.path.dirname(full), made_folders)
        if os.path.isdir(full):
            raise InputError(f"{option}: '{path}' is a folder")
        if os.path.exists(full) and not os.access(full, os.W_OK):
            raise InputError(f"{option}: cannot write '{full}' (permission denied)")
        if any(full == i or os.path.exists(full) and os.path.exists(i) and os.path.samefile(full, i) for i in inputs):
            raise InputError(f"{option} '{path}' is the input file, which is never written: choose another path")
        if full in seen:
            other_option, other_path = seen[full]
            raise InputError(f"{option} '{path}' and {other_option} '{other_path}' name the same file: "
                             "each output needs its own path")
        seen[full] = (option, path)

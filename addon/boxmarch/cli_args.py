"""The command line's arguments: the parser of every command (boxmarch.cli runs them)."""
from __future__ import annotations

import argparse

from . import core


class InputError(Exception):
    """Bad arguments or input: exit code 2 with this one-line message."""


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
    p.add_argument("--origin", choices=core.ORIGIN_MODES, default=core.ORIGIN_MODES[0])
    p.add_argument("--angle-epsilon", type=float, default=0.1, help="radians (default 0.1)")
    p.add_argument("--encoding", choices=core.ENCODINGS, default=core.ENCODINGS[0])
    p.add_argument("--domain", choices=("POINT", "CORNER"), default="POINT")
    p.add_argument("--axis-turn", type=int, default=0, choices=range(24), metavar="0..23")
    p.add_argument("--sort-axes-by-extent", action="store_true")
    p.add_argument("--no-cache", action="store_true", help="derive every frame (no copy cache)")
    p.add_argument("--full", action="store_true", help="re-bake unchanged submeshes too")
    p.add_argument("--parents", choices=core.HIERARCHY_RULES, default=core.HIERARCHY_RULES[0],
                   help="each box's parent: ATTRIBUTE (boxmarch_parent), CONTAINMENT or CHAIN")
    p.add_argument("--random-seed", type=int, default=0, help="seed of each box's random value (0..2^31-1)")


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
    from .layouts import LAYOUTS
    from .export.transforms import PRESETS

    p.add_argument("--preset", choices=sorted(PRESETS), default="GLTF")
    p.add_argument("--layout", choices=sorted(LAYOUTS), default=None,
                   help="channels to write (default: the preset's own, docs/ENGINES.md)")
    p.add_argument("--to", required=required, metavar="PATH", help="file to export (.fbx, .glb or .blend)")


def build_parser(description: str, runners: dict):
    """The parser of every command; ``runners`` = {command: the function that runs it}, set as
    the parsed arguments' ``run``."""
    parser = _Parser(prog="boxmarch", description=description)
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
    p.add_argument("--count", type=int, default=16000, help="number of boxes (default 16000)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="demo_out", help="folder for demo.blend and demo.glb (default ./demo_out)")
    p.add_argument("--preview", choices=("AUTO", "GPU", "CPU"), default="AUTO",
                   help="renderer of demo.png (AUTO: the GPU preview if a GPU context can be made)")
    p.add_argument("--json", metavar="REPORT.json")
    p.set_defaults(run=runners["demo"])
    return parser

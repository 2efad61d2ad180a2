"""Command line: ``python -m boxmarch demo`` (in a Python that has ``bpy``).

Progress goes to stderr, the result table to stdout. Exit codes: 0 success, 2 bad arguments or
input, 1 internal error.
"""
from __future__ import annotations

import argparse
import os
import sys
import time


def _progress(message: str) -> None:
    print(f"[boxmarch] {message}", file=sys.stderr, flush=True)


def _table(headers, rows) -> str:
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    fmt = lambda cells: "| " + " | ".join(str(c).ljust(w) for c, w in zip(cells, widths)) + " |"
    return "\n".join([fmt(headers), "|" + "|".join("-" * (w + 2) for w in widths) + "|", *map(fmt, rows)])


def demo(args) -> int:
    """Build a world of boxes (varied sizes and rotations, some exact translated copies), bake it
    headless through the add-on's operator in float and 8-bit colour, decode the stored data and
    print timings and decode errors; write the baked scene to OUT/demo.blend."""
    import bpy
    import numpy as np

    import boxmarch
    from boxmarch import mesh_io, scenes

    if args.count < 1:
        print("boxmarch: --count must be at least 1", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    rows = []
    start = time.perf_counter()
    _progress(f"building {args.count:,} boxes")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        boxmarch.register()
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
    path = os.path.abspath(os.path.join(args.out, "demo.blend"))
    bpy.ops.wm.save_as_mainfile(filepath=path)
    rows.append(["total", f"{time.perf_counter() - start:.3f} s", f"wrote {path}", ""])
    print(f"boxmarch demo: {args.count:,} boxes, Blender {bpy.app.version_string}")
    print(_table(["step", "time", "what", "accuracy"], rows))
    return 0


def main(argv=None) -> int:
    if argv is None:
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(prog="boxmarch", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    p = commands.add_parser("demo", help="build, bake and check a world of boxes")
    p.add_argument("--count", type=int, default=16000, help="number of boxes (default 16000)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="demo_out", help="folder for demo.blend (default ./demo_out)")
    p.set_defaults(run=demo)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:
        return 2 if exit_.code else 0
    try:
        return args.run(args)
    except Exception as error:  # internal error: one line, exit 1
        print(f"boxmarch: internal error: {error!r}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

"""The bake as a job: the operator (operators/bake.py), the command line and the demo all bake
through ``bake_meshes``."""
from __future__ import annotations

from typing import Callable

from . import mesh_io

REPORT_TOTALS = ("submeshes", "baked", "cache_hits", "unchanged", "not_selected", "degenerate")


def bake_meshes(meshes, settings: mesh_io.BakeSettings, selected_only: bool = False,
                progress: Callable[[int, int, str], None] | None = None) -> list[mesh_io.PreparedBake]:
    """Bake every mesh: compute all of them first, then write them all, so one mesh that cannot be
    baked leaves every mesh untouched (mesh_io.BakeInputError, nothing written). ``progress(step,
    steps, what)`` is called before each of the 2 x len(meshes) steps. Returns the written bakes
    (each with its ``report`` dict and its ``result``)."""
    progress = progress or (lambda _step, _steps, _what: None)
    steps = 2 * len(meshes)
    prepared = []
    for i, mesh in enumerate(meshes):
        progress(i, steps, f"computing {mesh.name} ({i + 1}/{len(meshes)}, {len(mesh.vertices):,} vertices)")
        prepared.append(mesh_io.prepare_bake(mesh, settings, selected_only=selected_only))
    for i, bake in enumerate(prepared):
        progress(len(meshes) + i, steps, f"writing {bake.mesh.name}")
        bake.write()
    progress(steps, steps, "done")
    return prepared


def report_totals(reports) -> dict:
    """Sums of the per-mesh report counts, and the worst decode error over them."""
    totals = {key: sum(r[key] for r in reports) for key in REPORT_TOTALS}
    totals["max_relative_error"] = max(r["max_relative_error"] for r in reports)
    return totals


def not_box_warnings(reports) -> list[str]:
    """One warning per baked mesh holding pieces that do not look like boxes (core.not_boxes):
    each piece is drawn as one box holding one shape, so a modelled shape baked as it is draws
    clipped to its own faces, and a shape made of loose pieces draws a fragment per piece.
    docs/TROUBLESHOOTING.md says what the figures mean."""
    warnings = []
    for r in reports:
        example = r.get("not_box_example")
        if not example:
            continue
        found, pieces = r["not_boxes"], r["submeshes"]
        figures = f"{example['vertices']:,} vertices, {example['off_box']:.0%} off its faces"
        if pieces == 1:
            head = f"mesh '{r['mesh']}' does not look like a box ({figures})"
        else:
            which = f"its {pieces:,} pieces" if found == pieces else f"{found:,} of its {pieces:,} pieces"
            verb = "does not look like a box" if found == 1 else "do not look like boxes"
            head = f"mesh '{r['mesh']}': {which} {verb} (piece {example['submesh']}: {figures})"
        warnings.append(f"{head}: model one box per shape, not the shape (docs/PREVIEW.md)")
    return warnings

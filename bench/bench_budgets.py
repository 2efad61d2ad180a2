"""Triangle budgets: a character wearing chains of 100, 500 and 2,000 links, its chain's triangles
as boxmarch boxes and as a triangle mesh of the same links at the boxes' error, against the
triangle limits of VRChat's avatar performance ranks (PC and Quest).

VRChat ranks an avatar by its triangles ("Polygons", counted in triangles) among other figures;
an avatar is in the best rank whose limit its count does not exceed, and Very Poor above the
Poor limit. Limits as VRChat publishes them (VRCHAT_TRIANGLE_LIMITS, with their source). On
Quest the default Minimum Displayed Performance Rank is Medium: an avatar ranked Poor or Very Poor
is not shown by default.

Boxes: 12 triangles a box (chain_data.TRIANGLES_PER_BOX). Mesh: the triangles a link needs at
the boxes' coverage error in the close-up view, read from the run-time-against-error curve's
points (``python3 -m bench.curve --json CURVE.json``; scene "close chain", the demo character's
chains seen close): per renderer, the boxes at the shipped defaults and the mesh of fewest
triangles whose coverage error is at most theirs, its triangles over the scene's links (where no
mesh measured reaches it, the finest one's, marked so); ``--boxes SETTING`` takes the boxes at
another of the curve's settings (e.g. "512 steps", the closed-form presets' target). The chain
alone is ranked: a body adds its own triangles. Always printed beside them: the coarsest mesh
that still reads as a link (a 3-sided tube on 6 rings, 36 triangles), a floor under any mesh's.

    PYTHONPATH=addon python3 -m bench.bench_budgets [--curve CURVE.json [--boxes SETTING]]
"""
import argparse
import json

from bench.bench_boxes_vs_triangles import link_mesh
from bench.chain_data import TRIANGLES_PER_BOX
from bench.common import table

LINK_COUNTS = (100, 500, 2000)
COARSEST_LINK = (3, 2)  # link_mesh(n, m): a 3-sided tube on 6 rings, the coarsest mesh with the link's hole
# https://creators.vrchat.com/avatars/avatar-performance-ranking-system/ ("Avatar Performance
# Ranks - Value Maximums per Rank", Polygons; source: vrchat-community/creator-docs,
# Docs/docs/avatars/avatar-performance-ranking-system.md at 723a30ab, page updated 2023-03-10).
# rank -> the most triangles it allows; above the last: Very Poor.
VRCHAT_TRIANGLE_LIMITS = {
    "PC": (("Excellent", 32_000), ("Good", 70_000), ("Medium", 70_000), ("Poor", 70_000)),
    "Quest": (("Excellent", 7_500), ("Good", 10_000), ("Medium", 15_000), ("Poor", 20_000)),
}


def rank(platform, triangles):
    """The best VRChat rank on ``platform`` whose triangle limit ``triangles`` does not exceed."""
    return next((name for name, limit in VRCHAT_TRIANGLE_LIMITS[platform] if triangles <= limit), "Very Poor")


def equal_error_per_link(points, renderer, scene="close chain", setting="defaults"):
    """(triangles a link, reached, the boxes' coverage error %) of the mesh at the boxes' coverage
    error in ``scene`` on ``renderer``, from the curve's points: the mesh of fewest triangles whose
    coverage error is at most the boxes' at ``setting`` (the start of a boxes point's setting;
    their shipped defaults) (reached), else the finest mesh measured (none measured reaches it)."""
    here = [p for p in points if p["renderer"] == renderer and p["scene"] == scene]
    boxes = next(p for p in here if p["method"] == "boxes" and p["setting"].startswith(setting))
    links = boxes["triangles"] // TRIANGLES_PER_BOX
    meshes = sorted((p for p in here if p["method"] == "mesh"), key=lambda p: p["triangles"])
    equal = next((p for p in meshes if p["coverage"] <= boxes["coverage"]), None)
    return (equal or meshes[-1])["triangles"] // links, equal is not None, boxes["coverage"]


def budget_rows(mesh_per_link, link_counts=LINK_COUNTS):
    """[(links, method, triangles, PC rank, Quest rank)]: the boxes, then a mesh per entry of
    ``mesh_per_link`` (label -> triangles a link)."""
    rows = []
    for links in link_counts:
        methods = [("boxes", TRIANGLES_PER_BOX)] + list(mesh_per_link.items())
        for method, per_link in methods:
            triangles = links * per_link
            rows.append((links, method, triangles, rank("PC", triangles), rank("Quest", triangles)))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curve", help="bench.curve's --json points (without: the coarsest mesh only)")
    parser.add_argument("--boxes", default="defaults", help="the boxes' setting in the curve (default: defaults)")
    args = parser.parse_args()
    n, m = COARSEST_LINK
    mesh_per_link = {f"mesh {n} x {2 * m + 2}, the coarsest that reads as a link": len(link_mesh(n, m)[2])}
    if args.curve:
        with open(args.curve, encoding="utf-8") as f:
            points = json.load(f)
        for renderer in dict.fromkeys(p["renderer"] for p in points):
            per_link, reached, error = equal_error_per_link(points, renderer, setting=args.boxes)
            label = (f"mesh at the boxes' error ({error:.3f} %), {renderer}"
                     + ("" if reached else ": none up to this reaches it"))
            mesh_per_link[label] = per_link
    limits = "; ".join(f"{platform}: " + ", ".join(f"{name} <= {limit:,}" for name, limit in ranks)
                       for platform, ranks in VRCHAT_TRIANGLE_LIMITS.items())
    print(f"VRChat triangle limits ({limits}; above: Very Poor)")
    print(table(["links", "method", "triangles a link", "triangles", "PC rank", "Quest rank"],
                [[f"{links:,}", method, f"{triangles // links:,}", f"{triangles:,}", pc, quest]
                 for links, method, triangles, pc, quest in budget_rows(mesh_per_link)]))


if __name__ == "__main__":
    main()

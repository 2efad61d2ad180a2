"""The quality knob: SDF evaluations against pixels changed, per setting and scene (CPU reference).

core.render_boxes draws each scene as the preview's shader does, every fragment marched (what the
renderers measured so far run: no early depth, file order), at each knob setting, and compares the
picture with the full-quality render (quality 1, same epsilon) and with the exact surface (quality
1, epsilon 1e-5, 256 steps). Per setting and scene:

* SDF evals/px: map() calls (march steps + 3 normal taps per hit) per covered pixel, and the ratio
  to quality 1's;
* coverage: pixels covered in one image only; colour: pixels covered in both whose colour moves
  by more than 1/255 in a channel; depth: pixels covered in both whose depth along the view axis
  moves by more than a tenth of a pixel's width at that depth; any: one of the three. Each as a
  share of the pixels covered in either image; whether any is at most 0.5 %;
* vs exact surface: the same "any" against the exact render, beside quality 1's own.

    PYTHONPATH=addon python3 -m bench.bench_quality [--size 480] [--epsilon 1e-3 1e-4]

Scenes (bench_gpu_cost.py's): the pile (4,000 LINK boxes in a 4 x 4 x 4 block, seen through),
the chain down the arm (258 LINK boxes, 25 turns stacked), the cloud (16,000 SPHERE boxes, camera
inside). Epsilon 1e-3 is the Blender preview's default, 1e-4 three.js's and Godot 3's.
"""
import argparse

import numpy as np

from bench.bench_gpu_cost import NEAR, linear_depth, scenes_to_measure
from boxmarch import core
from boxmarch.formats.transforms import matrix_quaternions

SCENES = ("pile", "chain down the arm", "cloud")
QUALITIES = (1.0, 0.75, 0.5, 0.25)
EXACT = {"epsilon": 1e-5, "max_steps": 256}


def pixel_width(depth, to_clip, height):
    """Width of one pixel (scene units) at each window depth, for bench_gpu_cost's perspective."""
    return 2.0 * linear_depth(depth) / (height * to_clip[1, 1])


def changes(result, reference, to_clip):
    """Shares of the pixels covered in either image: (coverage, colour, depth, any) changed."""
    a, b = result.depth < 1, reference.depth < 1
    either = max(int((a | b).sum()), 1)
    both = a & b
    colour = both & (np.abs(result.rgba[..., :3] - reference.rgba[..., :3]).max(-1) > 1 / 255)
    moved = np.abs(linear_depth(result.depth) - linear_depth(reference.depth))
    depth = both & (moved > 0.1 * pixel_width(np.minimum(reference.depth, 1 - 1e-7), to_clip, len(a)))
    coverage = a != b
    return tuple(100.0 * int(x.sum()) / either for x in (coverage, colour, depth, coverage | colour | depth))


def rows_for(name, scene, size, epsilon):
    origins, rotations, half, sdf, (to_clip, to_view, _eye) = scene
    quaternions = matrix_quaternions(rotations).astype(np.float32)

    def render(**options):
        march = {"epsilon": epsilon, "max_steps": 64, **options}
        return core.render_boxes(origins, quaternions, half, to_clip, to_view, size, size, sdf=sdf, **march)

    exact = render(**EXACT)
    full = None
    rows = []
    for quality in QUALITIES:
        result = render(quality=quality)
        full = full or result
        evals = result.cost["sdf_evaluations"] / max(result.cost["covered_pixels"], 1)
        ratio = result.cost["sdf_evaluations"] / full.cost["sdf_evaluations"]
        coverage, colour, depth, anything = changes(result, full, to_clip)
        rows.append([name, f"{epsilon:g}", f"{quality:g}", f"{evals:.1f} ({ratio:.2f}x)", f"{coverage:.2f}%",
                     f"{colour:.2f}%", f"{depth:.2f}%", f"{anything:.2f}%", "yes" if anything <= 0.5 else "no",
                     f"{changes(result, exact, to_clip)[3]:.2f}%"])
    return rows


HEADERS = ["scene", "epsilon", "quality", "SDF evals/px", "coverage", "colour", "depth", "any", "any <= 0.5 %",
           "vs exact surface"]


def main():
    from bench.common import table

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=480, help="image width and height in pixels")
    parser.add_argument("--epsilon", type=float, nargs="+", default=[1e-3, 1e-4])
    args = parser.parse_args()
    made = scenes_to_measure(args.size, far_boxes=1)
    rows = [row for epsilon in args.epsilon for name in SCENES for row in rows_for(name, made[name], args.size, epsilon)]
    print(f"{args.size} x {args.size} px, max_steps 64, every fragment marched (file order, no early depth); "
          f"changes against quality 1 at the same epsilon, last column against the exact surface (near {NEAR})")
    print(table(HEADERS, rows))


if __name__ == "__main__":
    main()

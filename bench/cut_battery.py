"""The differential battery's long form (tests/helpers/cut_battery.py; docs/BENCHMARKS.md, "Cuts that
change no pixel"): thousands of seeded scenes drawn by the Blender preview (bpy module) and three.js
r111 and r180 (headless Chromium), plain and with each cut; prints per renderer and cut the scenes
run, pixels compared, changed, explained (plain and cut agree at the large step budget) and
unexplained, the scenes with unexplained pixels, then a line per such scene (seed, renderer, cut,
counts, kinds).

    PYTHONPATH=addon python3 -m bench.cut_battery --scenes 2000 --renderer all
    PYTHONPATH=OTHER_CHECKOUT/addon python3 -m bench.cut_battery ...   # another worktree's add-on and shaders
    PYTHONPATH=addon python3 -m bench.cut_battery --generator mid-depth-ortho ...   # cut_battery.GENERATORS

Scenes are built in bpy processes of --chunk seeds each; three.js draws --batch scenes per page.
"""
import argparse
import tempfile
import time
from collections import defaultdict

from bench.common import table
from tests.helpers import cut_battery


def run(seeds, renderers, chunk, batch, log=print, generator=cut_battery.scene):
    """[Found, ...] of every seed in every renderer, and the seconds each renderer took."""
    found, seconds = [], defaultdict(float)
    three = [r for r in renderers if r != "preview"]
    for start in range(0, len(seeds), chunk):
        part = list(seeds[start:start + chunk])
        with tempfile.TemporaryDirectory(prefix="boxmarch-cut-battery-") as folder:
            began = time.perf_counter()
            drawn = cut_battery.draw_in_blender(part, folder, preview="preview" in renderers, export=bool(three),
                                                generator=generator)
            seconds["blender"] += time.perf_counter() - began
            for seed, arrays in drawn.items():
                if "error" in arrays:
                    log(f"seed {seed}: the scene did not build or draw: {arrays['error'].strip().splitlines()[-1]}")
                elif "preview" in renderers:
                    found += cut_battery.preview_findings(seed, arrays)
            for release in three:
                began = time.perf_counter()
                found += cut_battery.draw_in_threejs(part, folder, release, batch, generator=generator)
                seconds[release] += time.perf_counter() - began
        log(f"{min(start + chunk, len(seeds))} of {len(seeds)} scenes")
    return found, seconds


def summary(found):
    rows = []
    for renderer in cut_battery.RENDERERS:
        for cut in dict.fromkeys(f.cut for f in found if f.renderer == renderer):
            mine = [f for f in found if f.renderer == renderer and f.cut == cut]
            rows.append([renderer, cut, len(mine), sum(f.compared for f in mine), sum(f.changed for f in mine),
                         sum(f.explained for f in mine), sum(f.unexplained for f in mine),
                         sum(1 for f in mine if f.unexplained)])
    return table(["renderer", "cut", "scenes", "pixels compared", "changed", "explained", "unexplained",
                  "scenes failing"], rows)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=200)
    parser.add_argument("--first", type=int, default=0, help="first seed")
    parser.add_argument("--renderer", choices=("all", *cut_battery.RENDERERS), default="all")
    parser.add_argument("--chunk", type=int, default=200, help="seeds per bpy process")
    parser.add_argument("--batch", type=int, default=40, help="scenes per three.js page")
    parser.add_argument("--generator", choices=tuple(cut_battery.GENERATORS), default="battery",
                        help="the battery's scenes, or made hostile to the occluders' depth rounding")
    args = parser.parse_args(argv)
    renderers = cut_battery.RENDERERS if args.renderer == "all" else (args.renderer,)
    seeds = range(args.first, args.first + args.scenes)
    generator = cut_battery.GENERATORS[args.generator]
    found, seconds = run(seeds, renderers, args.chunk, args.batch, generator=generator)
    print(summary(found))
    print("seconds: " + ", ".join(f"{k} {v:.0f}" for k, v in seconds.items()))
    for f in found:
        if f.unexplained:
            print(f.line() + "  traits: " + ", ".join(generator(f.seed)["traits"]))


if __name__ == "__main__":
    main()

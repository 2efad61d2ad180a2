"""The Godot 3 box table as text (formats/godot.py, the GODOT3 preset's NAME.boxes.tres): time
and peak memory of writing it for N random boxes, each run in a fresh process (peak RSS from
/proc, less the process's size before the table was made).

With --base ADDON_FOLDER (the addon/ folder of another checkout, e.g. main's in a
`git worktree add /tmp/base main`), the same table is written by that checkout's godot module too,
in the same run: its image_texture_tres (the text as one string) where it has no
write_image_texture_tres. Both files are compared byte for byte.

    python3 -m bench.bench_godot_table [--base /tmp/base/addon] [N ...]   (default: 10000 100000 1000000)
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PLANES = 5  # layouts.TABLE_PLANES


def child(addon, boxes, path):
    """In a fresh process: write the table of ``boxes`` random boxes to ``path`` with the godot
    module of ``addon``; print {seconds, peak bytes, sha256}."""
    sys.path.insert(0, addon)
    import numpy as np

    from bench.common import reset_peak_rss, rss_bytes
    from boxmarch.formats import godot

    table = np.random.default_rng(0).standard_normal((boxes, PLANES, 4)).astype(np.float32)
    reset_peak_rss()
    base = rss_bytes("VmRSS")
    start = time.perf_counter()
    if hasattr(godot, "write_image_texture_tres"):
        godot.write_image_texture_tres(path, table)
    else:
        with open(path, "w") as f:
            f.write(godot.image_texture_tres(table))
    seconds = time.perf_counter() - start
    peak = rss_bytes("VmHWM") - base
    with open(path, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    print(json.dumps({"seconds": seconds, "peak": peak, "sha256": digest, "bytes": os.path.getsize(path)},
                     allow_nan=False))


def measure(addon, boxes, folder):
    path = os.path.join(folder, f"t{boxes}.tres")
    out = subprocess.run([sys.executable, "-m", "bench.bench_godot_table", "--child", addon, str(boxes), path],
                         cwd=ROOT, capture_output=True, text=True, check=True)
    os.remove(path)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    from bench.common import table

    parser = argparse.ArgumentParser()
    parser.add_argument("counts", nargs="*", type=int, default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--base", help="addon/ folder of the checkout to compare with")
    parser.add_argument("--child", nargs=3, metavar=("ADDON", "N", "PATH"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]), args.child[2])
        return
    checkouts = [("this checkout", os.path.join(ROOT, "addon"))] + ([("base", args.base)] if args.base else [])
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for boxes in args.counts:
            results = {name: measure(addon, boxes, folder) for name, addon in checkouts}
            same = len({r["sha256"] for r in results.values()}) == 1
            for name, r in results.items():
                rows.append([f"{boxes:,}", name, f"{r['bytes'] / 2**20:,.1f} MiB", f"{r['seconds']:.2f} s",
                             f"{r['peak'] / 2**20:,.0f} MiB", "yes" if same else "NO"])
    print(table(["boxes", "writer", "file", "time", "peak memory", "same bytes"], rows))


if __name__ == "__main__":
    main()

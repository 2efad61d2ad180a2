"""Degenerate scale (issue 14): merge per submesh on N coincident vertices and select-across with
an epsilon that joins everything, time and peak memory above the arrays themselves, beside
Blender's Merge by Distance (bpy.ops.mesh.remove_doubles) on the same vertices.

    python3 -m bench.bench_hostile [N]      (default 1000000)

The cost of the private copies the bindings take of every input the core reads without the GIL
(issue 21): ``core.bake`` of 125,000 and 1,000,000 random boxes, time and peak memory above the
inputs, with this checkout's package and, given ``--before DIR``, with the package importable
from DIR (e.g. the add-on folder of a build of the previous commit), in child processes run
alternately:

    python3 -m bench.bench_hostile --bake [--before DIR]

Each measurement runs in its own process, so its peak RSS (VmHWM) is its own.

The CONTAINMENT hierarchy (issue 36) on the layouts that cost it most beside random boxes, for
25,000 to 400,000 boxes (or the counts given; ``--scenes`` picks layouts by name): CPU time and its
growth from the count before (n log n: about 2.1x per doubling; n^(4/3), what lines crossing one
region of points cost a k-d tree: 2.52x; n^(5/3), planes: 3.17x), and the boxes given a parent.
Origins in one cube of side 200 unless said: random boxes 0.05 to 2 a side turned at random, long
thin boxes 200 x 0.01 x 0.01 along the x axis and turned at random, such boxes all crossing one
point (each origin on its own box's axis, up to 90 from the point), nested shells (one centre,
sizes 1.0001^k numbered in shuffled order, turned at random) and turned flat boxes 200 x 200 x
0.01. Run it with PYTHONPATH naming another build's add-on folder to time that build:

    python3 -m bench.bench_hostile --containment [--scenes random,thin-x,thin,thin-one-point,shells,flat] [BOXES ...]"""
import json
import os
import subprocess
import sys
import time

from bench.common import reset_peak_rss, rss_bytes, table  # noqa: E402


def child(case, n):
    import numpy as np

    if case == "blender":
        import bpy

        from boxmarch import mesh_io

        mesh = mesh_io.new_mesh("pile", np.zeros((n, 3), np.float32), np.zeros(0, np.int32),
                                np.zeros(0, np.int32), np.zeros(0, np.int32))
        ob = bpy.data.objects.new("pile", mesh)
        bpy.context.scene.collection.objects.link(ob)
        bpy.context.view_layer.objects.active = ob
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        base = rss_bytes()
        reset_peak_rss()
        start = time.perf_counter()
        bpy.ops.mesh.remove_doubles(threshold=1e-3)
        seconds = time.perf_counter() - start
        bpy.ops.object.mode_set(mode="OBJECT")
        result = len(mesh.vertices)
    else:
        from boxmarch import core

        if case == "merge":
            positions = np.zeros((n, 3), np.float32)
        else:
            positions = np.random.default_rng(0).random((n, 3)).astype(np.float32)
        sub = (np.arange(n) // 8).astype(np.int32) if case == "across" else np.zeros(n, np.int32)
        selected = np.zeros(n, np.uint8)
        selected[0] = 1
        base = rss_bytes()
        reset_peak_rss()
        start = time.perf_counter()
        if case == "merge":
            _, _, merged = core.merge_targets(positions, sub, 1, distance=1e-3)
            result = n - merged
        else:
            _, result = core.select_linked_across(positions, selected, sub, n // 8, epsilon=10.0)
        seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds, "peak": rss_bytes("VmHWM") - base, "result": result}, allow_nan=False))


def bake_child(count, repeats):
    """Peak memory of a first core.bake of `count` boxes in this process, then the wall and CPU
    time of `repeats` more."""
    from boxmarch import core, scenes

    arrays, *_ = scenes.random_boxes(count, seed=0)
    base = rss_bytes()
    reset_peak_rss()
    core.bake(*arrays)
    peak = rss_bytes("VmHWM") - base
    wall, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        core.bake(*arrays)
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    checks = []  # validate_mesh: the mesh checks, with the copies of this checkout
    for _ in range(10):
        start_cpu = time.process_time()
        core.validate_mesh(*arrays)
        checks.append(time.process_time() - start_cpu)
    print(json.dumps({"wall": wall, "cpu": cpu, "checks": checks, "peak": peak, "input": sum(a.nbytes for a in arrays)}, allow_nan=False))


def bake_rows(before, rounds=4):
    """Rows of the bake table: per box count, child processes of this checkout and of `before`
    alternately (`rounds` each, so load drifts hit both alike); the best and median wall time and
    the best CPU time (all threads) over every call, the best CPU time of validate_mesh (with the
    copies: their cost alone), and the peak memory of a first bake."""
    import statistics

    here = os.path.dirname(os.path.abspath(__file__))
    modules = [("this checkout", None)] + ([("before", os.path.abspath(before))] if before else [])
    rows = []
    for count, repeats in ((125_000, 5), (1_000_000, 2)):
        runs = {label: {"wall": [], "cpu": [], "checks": [], "peak": [], "input": 0} for label, _ in modules}
        for _ in range(rounds):
            for label, path in modules:
                env = dict(os.environ)
                if path:
                    env["PYTHONPATH"] = os.pathsep.join([path, here])
                out = subprocess.run([sys.executable, __file__, "--bake-child", str(count), str(repeats)],
                                     capture_output=True, text=True, env=env, check=True)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                for key in ("wall", "cpu", "checks"):
                    runs[label][key] += r[key]
                runs[label]["peak"].append(r["peak"])
                runs[label]["input"] = r["input"]
        stats = {}
        for label, _ in modules:
            r = runs[label]
            stats[label] = (min(r["wall"]), statistics.median(r["wall"]), min(r["cpu"]), min(r["checks"]),
                            min(r["peak"]))
            best, median, cpu, checks, peak = stats[label]
            rows.append([f"{count:,}", label, f"{best * 1e3:.1f}", f"{median * 1e3:.1f}", f"{cpu * 1e3:.1f}",
                         f"{checks * 1e3:.1f}", f"{peak / 2**20:.0f}", f"{r['input'] / 2**20:.0f}"])
        if before:
            now, then = stats["this checkout"], stats["before"]
            rows.append([f"{count:,}", "difference"] +
                        [f"{(a - b) * 1e3:+.1f} ({(a / b - 1) * 100:+.1f}%)" for a, b in zip(now[:4], then[:4])] +
                        [f"{(now[4] - then[4]) / 2**20:+.0f}", ""])
    return rows


CONTAINMENT_SCENES = {"random": "random 0.05-2, turned", "thin-x": "thin 200 x 0.01 x 0.01 along x",
                      "thin": "thin 200 x 0.01 x 0.01, turned", "thin-one-point": "thin, turned, crossing one point",
                      "shells": "nested shells, turned, shuffled", "flat": "flat 200 x 200 x 0.01, turned"}


def containment_scene(count, kind, seed=0):
    """(origins, quaternions, half-extents) of ``count`` boxes of one of CONTAINMENT_SCENES."""
    import numpy as np

    rng = np.random.default_rng(seed)
    origins = rng.uniform(-100, 100, (count, 3))
    turns = rng.normal(size=(count, 4))
    turns /= np.linalg.norm(turns, axis=1, keepdims=True)
    quaternions = turns.astype(np.float32)
    half = {"flat": [100.0, 100.0, 0.005], "random": None, "shells": None}.get(kind, [100.0, 0.005, 0.005])
    half = np.tile(half, (count, 1)) if half is not None else rng.uniform(0.05, 2.0, (count, 3)) / 2
    if kind == "thin-x":
        quaternions[:] = [0, 0, 0, 1]
    elif kind == "thin-one-point":  # the box's local x axis in object space, scaled by up to 90
        x, y, z, w = quaternions.astype(np.float64).T
        axis = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)], 1)
        origins = axis * rng.uniform(-90, 90, (count, 1))
    elif kind == "shells":
        origins[:] = 0.0
        half = np.tile(1.0001 ** rng.permutation(count)[:, None], (1, 3))
    return origins, quaternions, half


def containment_rows(counts, kinds):
    from boxmarch import core

    rows, before = [], {}
    for count in counts:
        for kind in kinds:
            origins, quaternions, half = containment_scene(count, kind)
            start = time.process_time()
            parent = core.box_hierarchy(origins, quaternions, half, rule="CONTAINMENT")[0]
            cpu = time.process_time() - start
            growth = f"{cpu / before[kind]:.2f}x" if before.get(kind) else ""
            before[kind] = cpu
            rows.append([f"{count:,}", CONTAINMENT_SCENES[kind], f"{cpu:.2f}", growth, f"{int((parent >= 0).sum()):,}"])
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def main(n):
    rows = []
    for case, label, result_label in (
            ("merge", f"boxmarch merge per submesh, {n:,} coincident vertices", "vertices left"),
            ("blender", f"Blender Merge by Distance (remove_doubles), same {n:,}", "vertices left"),
            ("across", f"boxmarch select across, {n:,} vertices, epsilon 10 (joins all)", "submeshes selected")):
        out = subprocess.run([sys.executable, __file__, "--child", case, str(n)], capture_output=True, text=True)
        if out.returncode != 0:
            rows.append([label, "failed", "", out.stderr.strip().splitlines()[-1:]])
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append([label, f"{r['seconds']:.3f} s", f"{r['peak'] / 2**20:.0f} MiB", f"{r['result']:,} {result_label}"])
    print(table(["run", "time", "peak memory above inputs", "result"], rows))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        child(sys.argv[2], int(sys.argv[3]))
    elif sys.argv[1:2] == ["--bake-child"]:
        bake_child(int(sys.argv[2]), int(sys.argv[3]))
    elif sys.argv[1:2] == ["--containment"]:
        args = sys.argv[2:]
        kinds = list(CONTAINMENT_SCENES)
        if "--scenes" in args:
            at = args.index("--scenes")
            kinds, args = args[at + 1].split(","), args[:at] + args[at + 2:]
        counts = [int(c) for c in args] or [25_000, 50_000, 100_000, 200_000, 400_000]
        print(table(["boxes", "scene", "CONTAINMENT CPU s", "growth", "boxes with a parent"],
                    containment_rows(counts, kinds)))
    elif sys.argv[1:2] == ["--bake"]:
        before = sys.argv[sys.argv.index("--before") + 1] if "--before" in sys.argv else None
        print(table(["boxes", "module", "core.bake best ms", "median ms", "best CPU ms", "validate_mesh CPU ms",
                     "peak MiB above inputs", "inputs MiB"],
                    bake_rows(before)))
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)

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

The CONTAINMENT hierarchy on randomly turned long thin boxes (200 x 0.01 x 0.01, issue 36) beside
as many random boxes (0.05 to 2 on a side), both with random rotations and origins in one cube of
side 200, for 100,000, 200,000 and 400,000 boxes (or the counts given): wall and CPU time, and
the CPU time's growth from the count before (n^(4/3) work, the bound this rule meets for lines
crossing one region, is 2.52x per doubling; linear is 2x):

    python3 -m bench.bench_hostile --containment [BOXES ...]"""
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


def containment_scene(count, kind, seed=0):
    """(origins, quaternions, half-extents) of ``count`` boxes turned at random, origins in a cube
    of side 200 (scenes.random_boxes' default spread): "thin" 200 x 0.01 x 0.01, "random" 0.05 to 2 a
    side."""
    import numpy as np

    rng = np.random.default_rng(seed)
    origins = rng.uniform(-100, 100, (count, 3))
    turns = rng.normal(size=(count, 4))
    turns /= np.linalg.norm(turns, axis=1, keepdims=True)
    half = np.tile([100.0, 0.005, 0.005], (count, 1)) if kind == "thin" else rng.uniform(0.05, 2.0, (count, 3)) / 2
    return origins, turns.astype(np.float32), half


def containment_rows(counts):
    from boxmarch import core

    rows, before = [], {}
    for count in counts:
        for kind in ("random", "thin"):
            origins, quaternions, half = containment_scene(count, kind)
            start, start_cpu = time.perf_counter(), time.process_time()
            parent = core.box_hierarchy(origins, quaternions, half, rule="CONTAINMENT")[0]
            wall, cpu = time.perf_counter() - start, time.process_time() - start_cpu
            growth = f"{cpu / before[kind]:.2f}x" if kind in before else ""
            before[kind] = cpu
            rows.append([f"{count:,}", "turned thin 200 x 0.01 x 0.01" if kind == "thin" else "random 0.05-2",
                         f"{wall:.2f}", f"{cpu:.2f}", growth, f"{int((parent >= 0).sum()):,}"])
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
        counts = [int(c) for c in sys.argv[2:]] or [100_000, 200_000, 400_000]
        print(table(["boxes", "scene", "CONTAINMENT wall s", "CPU s", "CPU growth", "boxes with a parent"],
                    containment_rows(counts)))
    elif sys.argv[1:2] == ["--bake"]:
        before = sys.argv[sys.argv.index("--before") + 1] if "--before" in sys.argv else None
        print(table(["boxes", "module", "core.bake best ms", "median ms", "best CPU ms", "validate_mesh CPU ms",
                     "peak MiB above inputs", "inputs MiB"],
                    bake_rows(before)))
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)

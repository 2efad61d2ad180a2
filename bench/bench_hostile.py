"""Degenerate scale (issue 14): merge per submesh on N coincident vertices and select-across with
an epsilon that joins everything, time and peak memory above the arrays themselves, beside
Blender's Merge by Distance (bpy.ops.mesh.remove_doubles) on the same vertices.

    python bench/bench_hostile.py [N]      (default 1000000)

Each measurement runs in its own process, so its peak RSS (VmHWM) is its own."""
import json
import subprocess
import sys
import time

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from common import reset_peak_rss, rss_bytes, table  # noqa: E402


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
    print(json.dumps({"seconds": seconds, "peak": rss_bytes("VmHWM") - base, "result": result}))


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
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)

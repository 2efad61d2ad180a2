"""Bake benchmark inside Blender (the bpy module): the operator against pure data transfer.

For N random boxes (8 vertices each) it prints the operator's time for a first bake, the time of
the pure data transfer the bake cannot avoid (foreach_get of positions plus foreach_set of the
three output attributes, with the same fast calls the add-on uses), their ratio, the same transfer
done by an operator called through bpy.ops as the bake is (and the re-bake's ratio to it), the floor
(that operator plus reading the topology layers: the least any bake operator does), the core's own
time, the peak extra memory of the bake against the size of the attributes it writes, and the
worst decode error of what Blender stores, for FLOAT_COLOR and BYTE_COLOR.

    python3 -m bench.bench_bake [N ...]     (default: 1000 16000 125000 1000000)

To compare with another version side by side (docs/BENCHMARKS.md quotes the bake before the
per-box parameters landed), run the same command with PYTHONPATH pointing at that checkout's
addon/ folder (built with scripts/dev_build.sh) right before or after this one.
"""
import sys
import time

import numpy as np

import bpy  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import core, mesh_io  # noqa: E402
from bench.common import best_of, boxes_object, decode_error, reset_peak_rss, rss_bytes, table  # noqa: E402


def transfer(mesh):
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    colour = np.empty(len(mesh.vertices) * 4, np.float32)
    uv = np.empty(len(mesh.loops) * 2, np.float32)

    def run():
        mesh.attributes["position"].data.foreach_get("vector", positions)
        mesh.color_attributes["BoxOffset"].data.foreach_set("color", colour)
        # UV maps through the attribute API, as the add-on writes them (uv_layer.uv would skip
        # the copy-on-write of shared arrays)
        mesh.attributes["BoxQuatXY"].data.foreach_set("vector", uv)
        mesh.attributes["BoxQuatZW"].data.foreach_set("vector", uv)
    return run


def read_topology_layers(mesh):
    """Read the three topology layers the bake reads (edge ends, corner vertices, corner edges)
    into fresh arrays, and nothing more: without them no bake can know its submeshes and faces."""
    arrays = []
    for name, count in ((".edge_verts", len(mesh.edges) * 2), (".corner_vert", len(mesh.loops)),
                        (".corner_edge", len(mesh.loops))):
        values = np.empty(count, np.int32)
        mesh.attributes[name].data.foreach_get("value", values)
        arrays.append(values)
    return arrays


class BENCH_OT_transfer(bpy.types.Operator):
    """The transfer alone as an operator (tagging the mesh as the bake does), called like the bake
    through bpy.ops: before each call Blender re-evaluates the changed mesh, which then shares its
    arrays with the evaluated copy, and the first RNA access to a shared layer copies it (see
    docs/BENCHMARKS.md). Any operator that touches these layers pays that; the plain transfer does not."""

    bl_idname = "bench.transfer"
    bl_label = "Transfer"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        mesh = context.object.data
        transfer(mesh)()
        mesh.update()
        return {"FINISHED"}


class BENCH_OT_floor(bpy.types.Operator):
    """The least any bake operator does: the transfer plus reading the topology, no computation.
    A bake through bpy.ops cannot be faster than this on the same Blender."""

    bl_idname = "bench.floor"
    bl_label = "Floor"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        mesh = context.object.data
        read_topology_layers(mesh)
        transfer(mesh)()
        mesh.update()
        return {"FINISHED"}


def fresh(count, repeats):
    """Best time of first bakes, each on a freshly built mesh (a first bake creates the layers)."""
    times, ob = [], None
    for _ in range(repeats):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        ob, centres, sizes = boxes_object(bpy, count)
        start = time.perf_counter()
        assert bpy.ops.boxmarch.bake(incremental=False) == {"FINISHED"}
        times.append(time.perf_counter() - start)
    return min(times), ob, centres, sizes


def main(counts):
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        boxmarch.register()
    bpy.utils.register_class(BENCH_OT_transfer)
    bpy.utils.register_class(BENCH_OT_floor)
    rows = []
    for count in counts:
        repeats = 5 if count <= 16000 else 1
        first, ob, centres, sizes = fresh(count, repeats)
        mesh = ob.data
        rebake = best_of(repeats, lambda: bpy.ops.boxmarch.bake(incremental=False))
        skip = best_of(repeats, lambda: bpy.ops.boxmarch.bake(incremental=True))
        arrays = (mesh_io.read_positions(mesh), *mesh_io.read_topology(mesh))
        core_time = best_of(repeats, lambda: core.bake(*arrays))  # noqa: F821 (called before the del below)
        truth = core.bake(*arrays)
        del arrays
        float_error = decode_error(mesh, truth.origins, truth.half_extents, raw_bytes=False)
        centre_error = float((np.linalg.norm(truth.origins - centres, axis=1) / (sizes.max(axis=1) / 2)).max())
        run_transfer = transfer(mesh)
        run_transfer()  # the first access after the last bake's evaluation un-shares the layers: not timed
        transfer_time = best_of(repeats, run_transfer)  # overwrites the baked data: measured last
        operator_transfer = best_of(repeats, bpy.ops.bench.transfer)
        floor = best_of(repeats, bpy.ops.bench.floor)
        rebake_after_transfer = best_of(repeats, lambda: bpy.ops.boxmarch.bake(incremental=False))

        bpy.ops.wm.read_factory_settings(use_empty=True)
        ob, centres, sizes = boxes_object(bpy, count)
        mesh = ob.data
        written = len(mesh.vertices) * 16 + len(mesh.loops) * 8 * 3  # BoxOffset + UVMap + 2 quaternion maps
        base = rss_bytes()
        reset_peak_rss()
        assert bpy.ops.boxmarch.bake(encoding="FLOAT_COLOR") == {"FINISHED"}
        peak = rss_bytes("VmHWM") - base
        assert bpy.ops.boxmarch.bake(encoding="BYTE_COLOR", incremental=False) == {"FINISHED"}
        byte_error = decode_error(mesh, truth.origins, truth.half_extents, raw_bytes=True)
        del truth
        rebake = min(rebake, rebake_after_transfer)
        rows.append([f"{count:,}", f"{first * 1e3:.1f}", f"{rebake * 1e3:.1f}", f"{skip * 1e3:.1f}",
                     f"{transfer_time * 1e3:.2f}", f"{first / transfer_time:.1f}x", f"{rebake / transfer_time:.1f}x",
                     f"{operator_transfer * 1e3:.2f}", f"{rebake / operator_transfer:.1f}x",
                     f"{floor * 1e3:.2f}", f"{floor / transfer_time:.1f}x", f"{first / floor:.1f}x", f"{rebake / floor:.1f}x",
                     f"{core_time * 1e3:.1f}",
                     f"{peak / 2**20:.0f}", f"{written / 2**20:.0f}", f"{peak / written:.2f}",
                     f"{float_error:.1e}", f"{byte_error:.1e}", f"{centre_error:.1e}"])
        print(f"done {count}", file=sys.stderr, flush=True)
    print(f"Blender {bpy.app.version_string}, boxes of 0.05-2 units within 100 units of the origin; times in ms (best of runs)")
    print(table(["boxes", "bake (first)", "re-bake", "re-bake, unchanged", "transfer", "bake / transfer",
                 "re-bake / transfer", "transfer as operator", "re-bake / operator transfer",
                 "floor operator", "floor / transfer", "bake / floor", "re-bake / floor", "core only", "peak extra MiB", "attributes MiB",
                 "peak / attributes",
                 "decode error float", "decode error 8-bit", "origin vs generated centre"], rows))
    print("decode error: |decoded origin - baked origin| / largest half-extent, decoding the stored attributes "
          "in float64; origin vs generated centre: the float64 centre the boxes were generated around, which "
          "float32 vertex storage alone moves by up to |centre| * 2^-24 per coordinate")


if __name__ == "__main__":
    main([int(n) for n in sys.argv[1:]] or [1000, 16000, 125000, 1000000])

"""Submesh tools benchmark inside Blender (the bpy module): each operator end to end in Edit Mode
(leaving and re-entering Edit Mode included) beside Blender's nearest built-in on the same mesh
in the same run, then the core alone, and the hash grid against nanoflann radius searches.

    python3 -m bench.bench_tools [BOXES ...]     (default: 1000 16000 125000)

Meshes: BOXES random boxes (8 vertices each) for the select tools and the UV packing (every face
its own UV island); the same count with 10% of them jittered copies (1e-5) for dedup; boxes whose
+x face has its own copies of two corners (10 vertices each, 0.8 x BOXES of them: the same vertex
count) for merge; a path with BOXES cube instances for instance-on-curve."""
import sys
import time

import numpy as np

import bpy  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import core, mesh_io, scenes  # noqa: E402
from bench.common import table  # noqa: E402


def place(mesh, name="bench"):
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    for other in bpy.context.scene.objects:
        other.select_set(other == ob)
    bpy.context.view_layer.objects.active = ob
    return ob


def boxes_mesh(count, seed=0):
    (positions, _e, starts, sizes, corners), _, _, _ = scenes.random_boxes(count, seed=seed)
    return mesh_io.new_mesh("boxes", positions, starts, sizes, corners)


def dedup_mesh(count, seed=0):
    originals = count - count // 10
    (positions, _e, starts, sizes, corners), _, _, _ = scenes.random_boxes(originals, seed=seed)
    rng = np.random.default_rng(seed)
    copies = positions[: 8 * (count // 10)].astype(np.float64)
    jitter = rng.normal(size=copies.shape)
    copies += 1e-5 * jitter / np.linalg.norm(jitter, axis=1, keepdims=True)
    all_positions = np.concatenate([positions, copies.astype(np.float32)])
    n = count // 10
    return mesh_io.new_mesh("dups", all_positions, np.arange(0, 24 * count, 4, dtype=np.int32),
                            np.full(6 * count, 4, np.int32),
                            np.concatenate([corners, corners[: 24 * n] + 8 * originals]))


def merge_mesh(count, seed=0):
    """count boxes of 10 vertices: the +x face uses copies of corners 4 and 6 (within 1e-4)."""
    (positions, _e, starts, sizes, corners), _, _, _ = scenes.random_boxes(count, seed=seed)
    rng = np.random.default_rng(seed)
    originals = positions.reshape(count, 8, 3)
    copies = originals[:, [4, 6]] + rng.uniform(-1e-4, 1e-4, (count, 2, 3)).astype(np.float32)
    quads = np.array([[0, 1, 3, 2], [8, 9, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
    corner_verts = (quads[None] + 10 * np.arange(count)[:, None, None]).reshape(-1).astype(np.int32)
    return mesh_io.new_mesh("split", np.concatenate([originals, copies], 1).reshape(-1, 3), starts, sizes, corner_verts)


def uv_mesh(count, seed=0):
    mesh = boxes_mesh(count, seed)
    mesh.uv_layers.new(name="UVMap")
    rng = np.random.default_rng(seed)
    faces = 6 * count
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)[None]
    uv = rng.uniform(0, 3, (faces, 1, 2)) + square * rng.uniform(0.1, 1.0, (faces, 1, 2))
    mesh.uv_layers["UVMap"].uv.foreach_set("vector", uv.reshape(-1).astype(np.float32))
    return mesh


def select_every(ob, step):
    """Object Mode: select vertex 0 of every `step` vertices, and nothing else."""
    mesh = ob.data
    for name in (".select_vert", ".select_edge", ".select_poly"):
        if name in mesh.attributes:
            mesh.attributes.remove(mesh.attributes[name])
    select = np.zeros(len(mesh.vertices), bool)
    select[::step] = True
    mesh.vertices.foreach_set("select", select)


def timed_in_edit(make_mesh, prepare, action, repeats):
    """Best time of `action` run in Edit Mode on a fresh mesh each repeat."""
    best = float("inf")
    for _ in range(repeats):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        ob = place(make_mesh())
        prepare(ob)
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_mode(type="VERT")
        start = time.perf_counter()
        result = action()
        best = min(best, time.perf_counter() - start)
        assert result == {"FINISHED"}, result
        bpy.ops.object.mode_set(mode="OBJECT")
    return best


def select_all(_ob):
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.object.mode_set(mode="OBJECT")


def instance_on_curve(count):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=0.01)
    cube = bpy.context.active_object
    bpy.ops.curve.primitive_nurbs_path_add()  # length 4
    start = time.perf_counter()
    result = bpy.ops.boxmarch.add_instance_on_curve(instance=cube.name, spacing=4.0 / (count - 1), convert_to_mesh=True)
    elapsed = time.perf_counter() - start
    # the path's evaluated length is 4 within float rounding: one copy more or less at the end
    assert result == {"FINISHED"} and abs(len(bpy.context.active_object.data.vertices) - 8 * count) <= 8
    return elapsed


def best(repeats, fn):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def ms(seconds):
    return f"{seconds * 1e3:.0f}" if seconds >= 0.1 else f"{seconds * 1e3:.1f}"


PACK_ISLANDS_LIMIT = 16000


def main(counts):
    if not hasattr(bpy.types, "BOXMARCH_OT_select_linked_submeshes"):
        boxmarch.register()
    op_rows, core_rows = [], []
    for count in counts:
        repeats = 3 if count <= 16000 else 4
        merge_boxes = count * 8 // 10
        every_box = lambda ob: select_every(ob, 8)
        ours = {
            "select linked submeshes": timed_in_edit(lambda: boxes_mesh(count), every_box,
                                                     bpy.ops.boxmarch.select_linked_submeshes, repeats),
            "select linked across": timed_in_edit(lambda: boxes_mesh(count), every_box,
                                                  lambda: bpy.ops.boxmarch.select_linked_across(epsilon=1e-4), repeats),
            "dedup submeshes": timed_in_edit(lambda: dedup_mesh(count), select_all,
                                             lambda: bpy.ops.boxmarch.dedup_submeshes(tolerance=1e-4), repeats),
            "merge by distance per submesh": timed_in_edit(lambda: merge_mesh(merge_boxes), select_all,
                                                           lambda: bpy.ops.boxmarch.merge_by_distance_submeshes(distance=1e-3), repeats),
            "pack UVs by Z": timed_in_edit(lambda: uv_mesh(count), select_all,
                                           lambda: bpy.ops.boxmarch.pack_uv_by_z(padding=0.0005), repeats),
            "instance on curve (+ convert)": best(repeats, lambda: instance_on_curve(count)),
        }
        builtin = {
            "select linked submeshes": ("Select Linked", timed_in_edit(lambda: boxes_mesh(count), every_box,
                                                                        bpy.ops.mesh.select_linked, repeats)),
            "dedup submeshes": ("Merge by Distance, whole mesh", timed_in_edit(
                lambda: dedup_mesh(count), select_all, lambda: bpy.ops.mesh.remove_doubles(threshold=1e-4), repeats)),
            "merge by distance per submesh": ("Merge by Distance, whole mesh", timed_in_edit(
                lambda: merge_mesh(merge_boxes), select_all, lambda: bpy.ops.mesh.remove_doubles(threshold=1e-3), repeats)),
        }
        if count <= PACK_ISLANDS_LIMIT:  # 2 s at 1,000 boxes and growing faster than linearly
            builtin["pack UVs by Z"] = ("Pack Islands", timed_in_edit(
                lambda: uv_mesh(count), select_all, lambda: bpy.ops.uv.pack_islands(margin=0.001), 1))
        else:
            builtin["pack UVs by Z"] = (f"Pack Islands (not run above {PACK_ISLANDS_LIMIT:,} boxes)", None)
        builtin["select linked across"] = builtin["select linked submeshes"]
        for name, seconds in ours.items():
            label, theirs = builtin.get(name, ("-", None))
            op_rows.append([f"{count:,}", name, ms(seconds), label, "-" if theirs is None else ms(theirs)])

        # The core alone on the plain boxes mesh (8 x count points).
        (positions, *topology), _, _, _ = scenes.random_boxes(count, seed=0)
        ids, n = core.find_submeshes(positions, *topology)
        selected = np.zeros(len(positions), bool)
        selected[::8] = True
        dups = dedup_mesh(count)
        dup_positions = mesh_io.read_positions(dups)
        dup_ids, dup_n = core.find_submeshes(dup_positions, *mesh_io.read_topology(dups))
        bpy.data.meshes.remove(dups)
        core_rows.append([
            f"{len(positions):,}",
            ms(best(repeats, lambda: core.select_linked_across(positions, selected, ids, n, 1e-4))),
            ms(best(repeats, lambda: core.find_duplicate_submeshes(dup_positions, dup_ids, dup_n, tolerance=1e-4))),
            ms(best(repeats, lambda: core.find_close_pairs(positions, 1e-4, method="HASH", threads=1))),
            ms(best(repeats, lambda: core.find_close_pairs(positions, 1e-4, method="HASH"))),
            ms(best(repeats, lambda: core.find_close_pairs(positions, 1e-4, method="KDTREE"))),
            ms(best(repeats, lambda: core.find_close_pairs(positions, 0.05, method="HASH", threads=1))),
            ms(best(repeats, lambda: core.find_close_pairs(positions, 0.05, method="KDTREE"))),
        ])
        print(f"done {count}: {op_rows[-6:]} {core_rows[-1]}", file=sys.stderr, flush=True)
    print(f"Blender {bpy.app.version_string}; times in ms, best of runs; operators end to end from Edit Mode")
    print(table(["boxes", "operator", "boxmarch", "Blender built-in", "built-in"], op_rows))
    print()
    print(table(["points", "select across core", "dedup core", "pairs hash 1 thread r=1e-4", "pairs hash 2 threads",
                 "pairs nanoflann r=1e-4", "pairs hash 1 thread r=0.05", "pairs nanoflann r=0.05"], core_rows))


if __name__ == "__main__":
    main([int(n) for n in sys.argv[1:]] or [1000, 16000, 125000])

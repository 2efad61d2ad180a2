"""Per-box parameters and hierarchy: what they add to a bake (the core alone, and the whole bake
job in Blender through the bpy module with painted attributes).

    python3 -m bench.bench_box_params [BOXES ...]     (default: 1000 16000)
    python3 -m bench.bench_box_params --searches [BOXES ...]   (the search tables alone)

Meshes: BOXES random boxes (8 vertices each) with boxmarch_shape painted per face and
boxmarch_user per vertex (one face in a hundred boxes disagreeing). A second table times the
geometric hierarchy rules on BOXES boxes arranged to crowd a grid, a third nearest_rows on
BOXES points among BOXES candidates, near and far from them."""
import sys

import numpy as np

import bpy  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import bake_job, core, mesh_io, scenes  # noqa: E402
from bench.common import best_of, boxes_object, table  # noqa: E402


BONES = 32


def core_rows(count):
    arrays, _centres, _sizes, _rotations = scenes.random_boxes(count, seed=1)
    result = core.bake(*arrays)
    sv = result.submesh_of_vertex
    faces = np.repeat(np.arange(count) % 7, 6).astype(np.float32)
    face_box = sv[arrays[4][arrays[2]]]
    boxes = (result.origins, result.quaternions, result.half_extents)
    rows = [(f"{count:,}", "bake (core)", best_of(3, lambda: core.bake(*arrays)))]
    rows.append((f"{count:,}", "reduce per submesh (1 float per face)",
                 best_of(3, lambda: core.reduce_per_submesh(faces, face_box, count))))
    rows.append((f"{count:,}", "random (fingerprints + hash)",
                 best_of(3, lambda: core.box_random(core.box_fingerprints(result.fingerprints, sv, count)))))
    for rule in ("ATTRIBUTE", "CONTAINMENT", "CHAIN"):
        rows.append((f"{count:,}", f"hierarchy {rule}", best_of(1, lambda: core.box_hierarchy(*boxes, rule=rule))))
    chain = np.arange(BONES) - 1  # BONES: the boxes spread over a chain of bones, box k on bone k % BONES
    rows.append((f"{count:,}", f"hierarchy BONES ({BONES}-bone chain)", best_of(1, lambda: core.box_hierarchy(
        *boxes, rule="BONES", given_parent=core.parents_by_bone(np.arange(count) % BONES, chain, result.origins)))))
    return rows


def hierarchy_stress_rows(count):
    """The geometric rules on scenes that crowd a grid: every box at one origin (equal sizes),
    boxes nested like dolls (numbered in shuffled order), small boxes along a helix, long thin
    rods (half-extents 5 x 0.005 x 0.005, turned at random) crossing one unit cube, and four
    clusters of small boxes 1e9 apart (numbered across them in turn)."""
    rng = np.random.default_rng(1)
    t = np.linspace(0, 50, count)
    identity = np.tile(np.float32([0, 0, 0, 1]), (count, 1))
    turned = rng.normal(size=(count, 4)).astype(np.float32)
    turned /= np.linalg.norm(turned, axis=1, keepdims=True)
    clusters = rng.random((count, 3))
    clusters[:, 0] += 1e9 * (np.arange(count) % 4)
    scenes_by_name = {
        "equal boxes at one origin": (np.zeros((count, 3)), identity, np.ones((count, 3))),
        "nested boxes, shuffled": (np.zeros((count, 3)), identity, np.repeat(
            rng.permutation(1.0001 ** np.arange(count))[:, None], 3, 1)),
        "boxes along a helix": (np.stack([np.cos(t), np.sin(t), t / 10], 1), identity, np.full((count, 3), 0.01)),
        "thin rods crossing one region": (rng.random((count, 3)), turned, np.tile([5.0, 0.005, 0.005], (count, 1))),
        "clusters 1e9 apart": (clusters, identity, np.full((count, 3), 0.01)),
    }
    rows = []
    for name, (origins, quaternions, half) in scenes_by_name.items():
        seconds = [best_of(1, lambda rule=rule: core.box_hierarchy(origins, quaternions, half, rule=rule))
                   for rule in ("CONTAINMENT", "CHAIN")]
        rows.append((f"{count:,}", name, *seconds))
    return rows


def nearest_rows(count):
    """core.nearest_rows for ``count`` points among ``count`` candidates (random in a unit cube,
    as the boxes of one object): the points on the candidates, 10 units off and 1e9 units off
    (object parenting's children away from the parent's boxes)."""
    candidates = np.random.default_rng(2).random((count, 3))
    return [(f"{count:,}", f"{offset:g} off", best_of(1, lambda offset=offset: core.nearest_rows(
        candidates + [offset, 0, 0], candidates))) for offset in (0, 10, 1e9)]


def job_rows(count):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    plain = boxes_object(bpy, count, name="plain")[0].data
    settings = mesh_io.BakeSettings(incremental=False)
    rows = [(f"{count:,}", "bake job, nothing painted (full)", best_of(3, lambda: bake_job.bake_meshes([plain], settings)))]
    ob, _centres, _sizes = boxes_object(bpy, count)
    mesh = ob.data
    shape = np.repeat(np.arange(count) % 7, 6).astype(np.int32)
    shape[6 * np.arange(0, count, 100)] = 9
    mesh.attributes.new("boxmarch_shape", "INT", "FACE").data.foreach_set("value", shape)
    mesh.attributes.new("boxmarch_user", "FLOAT", "POINT").data.foreach_set(
        "value", np.repeat(np.linspace(0, 1, count), 8).astype(np.float32))
    full = best_of(3, lambda: bake_job.bake_meshes([mesh], settings))
    unchanged = best_of(3, lambda: bake_job.bake_meshes([mesh], mesh_io.BakeSettings()))
    report = bake_job.bake_meshes([mesh], settings)[0].report["boxes"]
    flagged = report["disagreeing_attributes"]["boxmarch_shape"]["submeshes"]
    return rows + [(f"{count:,}", "bake job, painted (full)", full),
            (f"{count:,}", f"bake job, painted (unchanged: params only; {flagged} disagreeing boxes reported)",
             unchanged)]


def search_tables(counts):
    stress = [row for count in counts for row in hierarchy_stress_rows(count)]
    print(table(["boxes", "scene", "CONTAINMENT s", "CHAIN s"], [(b, s, f"{a:.4f}", f"{c:.4f}") for b, s, a, c in stress]))
    print()
    nearest = [row for count in counts for row in nearest_rows(count)]
    print(table(["points x candidates", "points", "nearest_rows s"], [(b, s, f"{t:.4f}") for b, s, t in nearest]))


def main(counts):
    boxmarch.register()
    rows = []
    for count in counts:
        rows += core_rows(count) + job_rows(count)
    print(table(["boxes", "step", "seconds"], [(b, s, f"{t:.4f}") for b, s, t in rows]))
    print()
    search_tables(counts)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--searches"]:  # the search tables alone (no Blender scene)
        search_tables([int(a) for a in sys.argv[2:]] or [1000, 16000])
    else:
        main([int(a) for a in sys.argv[1:]] or [1000, 16000])

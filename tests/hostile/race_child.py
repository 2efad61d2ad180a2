"""Child of tests/test_hostile_core2.py: one function of the NumPy API (boxmarch.core) called again
and again while another Python thread keeps writing a bad value (an index out of range, NaN, a
negative half-extent) into one of its input arrays and putting the valid values back. The core
runs without the GIL, so the writer runs during the call.

    python race_child.py CASE CALLS

Prints 'CASE results errors' (calls that returned, calls refused with ValueError). For a function
that refuses the bad value, a returned result must equal the one computed from the untouched
arrays, or the child exits 3; for one that refuses nothing in that array (CHECKS_NOTHING: plain
NumPy arithmetic, or a call holding the GIL), it must have the untouched result's shapes and
types. Any other exception propagates (exit 1); a crash shows as death by a signal.

CASES names, for each case, the public function it calls: the test fails when a public function
of boxmarch.core, core_boxes, core_render or core_tools has no case (or is in TAKES_NO_ARRAY)."""
import dataclasses
import sys
import threading

import numpy as np

from boxmarch import core, scenes

# case -> the public function it races
CASES = {
    "bake": "bake", "bake-faces": "bake", "bake-edges": "bake", "submeshes": "find_submeshes",
    "validate": "validate_mesh", "face-offsets": "face_offsets_from_corner_edges", "corner-uv": "corner_quaternion_uv",
    "across": "select_linked_across", "across-nan": "select_linked_across", "linked": "select_linked_submeshes",
    "dedup": "find_duplicate_submeshes", "merge": "merge_targets", "merge-passes": "merge_passes", "weld": "weld",
    "remove": "remove_vertices", "pack-uv": "pack_uv_by_height", "pairs-nan": "find_close_pairs",
    "reduce": "reduce_per_submesh", "fingerprints": "box_fingerprints", "random": "box_random",
    "dominant": "dominant_per_submesh", "nearest": "nearest_rows", "bones": "parents_by_bone",
    "hierarchy-given": "box_hierarchy", "hierarchy-containment": "box_hierarchy", "hierarchy-chain": "box_hierarchy",
    "raymarch": "raymarch", "sdf": "sdf_distance", "render": "render_boxes", "render-order": "render_boxes",
    "render-shapes": "render_boxes_by_shape", "render-baked": "render_baked_mesh", "boxes": "boxes_from_bake",
    "vertex-values": "vertex_values_from_corners", "rotate": "rotate_vector", "decode": "decode_offsets",
    "front-to-back": "front_to_back", "presets": "preset_of_shape", "not-boxes": "not_boxes",
    "occluders": "occluder_boxes",
}
# Cases whose function checks nothing in the spoiled array: any values are valid input.
CHECKS_NOTHING = {"random", "sdf", "rotate", "decode", "front-to-back", "presets"}
# Public functions without an array argument: nothing to race.
TAKES_NO_ARRAY = {"axis_turn_matrices", "axis_turn_label"}


def mesh(count=3000):
    arrays, *_ = scenes.random_boxes(count, seed=4, spread=20.0)
    return [np.ascontiguousarray(a) for a in arrays]


def box_cases():
    """Cases of the per-box functions and the renderers, on 3,000 and 40 boxes."""
    positions, edges, face_starts, face_sizes, corner_verts = small = mesh()
    result = core.bake(*small)
    sv, count = result.submesh_of_vertex, result.submesh_count
    many_ids = np.arange(2 * 10**6, dtype=np.int32) // 8  # the reduction is quick: a large input widens the race
    many_values = np.ones(len(many_ids), np.float32)
    fingerprints = np.ascontiguousarray(result.fingerprints)
    box_fp = core.box_fingerprints(fingerprints, sv, count)
    weights = np.ascontiguousarray(np.random.default_rng(3).random((len(positions), 4)))
    origins, quaternions = result.origins.copy(), result.quaternions.copy()
    half = result.half_extents.copy()
    given = np.arange(-1, count - 1, dtype=np.int32)
    box_bone = np.ascontiguousarray(np.arange(count) % 4, np.int64)
    points = np.ascontiguousarray(origins + 0.25)
    eye = np.eye(4, dtype=np.float32)
    eye[2, 3] = -30.0
    view = eye.copy()
    clip = np.diag(np.float32([0.05, 0.05, -0.01, 1.0])) @ view
    few_origins = np.ascontiguousarray(origins[:40], np.float32)
    few_q, few_h = quaternions[:40].copy(), np.ascontiguousarray(half[:40], np.float32)
    order = np.arange(40, dtype=np.int32)
    shapes = np.ascontiguousarray(np.arange(40) % 7, np.float32)
    rays = np.ascontiguousarray(np.random.default_rng(5).normal(size=(200, 3)), np.float32)
    corner_q = np.zeros((len(corner_verts), 4), np.float32)
    corner_q[:, 3] = 1.0
    offsets = np.ascontiguousarray(core.bake(*small).offsets)

    # Pieces of 24 vertices (three boxes' corners each, scaled): not_boxes measures pieces above 8.
    tori_positions = np.ascontiguousarray(np.concatenate([positions[:3000], positions[:3000] * 0.5,
                                                          positions[:3000] * 0.25]))
    tori_sv = np.ascontiguousarray(np.tile(sv[:3000], 3), np.int64)
    tori_q = quaternions.copy()

    def render(**options):
        return core.render_boxes(few_origins, few_q, few_h, clip, view, 24, 24, **options)

    return {
        "reduce": (lambda: core.reduce_per_submesh(many_values, many_ids, len(many_ids) // 8)[:2], many_ids, 2**30),
        "fingerprints": (lambda: core.box_fingerprints(fingerprints, sv, count), sv, 2**30),
        "random": (lambda: core.box_random(box_fp, 7), box_fp, 2**31),
        "dominant": (lambda: core.dominant_per_submesh(weights, sv, count), sv, -2**30),
        "nearest": (lambda: core.nearest_rows(points, origins), points, np.nan),
        "bones": (lambda: core.parents_by_bone(box_bone, [-1, 0, 1, 2], origins), box_bone, 2**40),
        "hierarchy-given": (lambda: core.box_hierarchy(origins, quaternions, half, "ATTRIBUTE", given)[0], given, 2**30),
        "hierarchy-containment": (lambda: core.box_hierarchy(origins, quaternions, half, "CONTAINMENT")[0], half, -1.0),
        "hierarchy-chain": (lambda: core.box_hierarchy(origins, quaternions, half, "CHAIN")[0], half, np.nan),
        "raymarch": (lambda: core.raymarch(rays, -rays, [1.0, 0.6, 0.2]).positions, rays, np.nan),
        "sdf": (lambda: core.sdf_distance("BOX", rays, [1.0, 0.6, 0.2]), rays, np.nan),
        "occluders": (lambda: core.occluder_boxes("LINK", half)[1], half, np.nan),
        "render": (lambda: render().depth, few_origins, np.nan),
        "render-order": (lambda: render(order=order).depth, order, 2**30),
        "render-shapes": (lambda: core.render_boxes_by_shape(few_origins, few_q, few_h, shapes, clip, view, 24, 24)
                          .depth, few_origins, np.nan),
        "render-baked": (lambda: core.render_baked_mesh(positions, offsets, corner_verts, corner_q, sv, clip, view,
                                                        24, 24).depth, sv, 2**30),
        "boxes": (lambda: core.boxes_from_bake(positions, offsets, corner_q[:len(positions)], sv), sv, 2**30),
        "vertex-values": (lambda: core.vertex_values_from_corners(corner_q, corner_verts, len(positions)),
                          corner_verts, 2**30),
        "rotate": (lambda: core.rotate_vector(points, quaternions), points, np.nan),
        "decode": (lambda: core.decode_offsets(offsets), offsets, np.nan),
        "front-to-back": (lambda: core.front_to_back(origins, [0.0, 0.0, 50.0, 1.0]), origins, np.nan),
        "presets": (lambda: core.preset_of_shape(shapes), shapes, np.nan),
        "not-boxes": (lambda: core.not_boxes(tori_positions, tori_sv, tori_q), tori_sv, 2**30),
    }


def cases(case):
    """The case's (call, the array the writer spoils, the spoiling value)."""
    built = box_cases()
    return built[case] if case in built else mesh_cases()[case]


def mesh_cases():
    """Cases of the mesh functions and the submesh tools, on 3,000 boxes."""
    positions, edges, face_starts, face_sizes, corner_verts = mesh()
    sub, count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    n = len(positions)
    selected = np.zeros(n, np.uint8)
    selected[::50] = 1
    target = np.arange(n, dtype=np.int32)
    corner_uv = np.zeros((len(corner_verts), 2), np.float32)
    result = core.bake(positions, edges, face_starts, face_sizes, corner_verts)
    corner_edges = np.ascontiguousarray(np.arange(len(corner_verts)) % len(edges), np.int32)
    remove = np.zeros(n, bool)
    remove[::9] = True
    height = np.ascontiguousarray(positions[:, 2])
    mesh_arrays = (positions, edges, face_starts, face_sizes, corner_verts)

    def bake():
        r = core.bake(positions, edges, face_starts, face_sizes, corner_verts)
        return r.offsets, r.quaternions

    def corner_uv_call():
        out = np.zeros_like(corner_uv)
        core.corner_quaternion_uv(out, 0, corner_verts, result, write_all=True)
        return out

    def pack_uv():
        out = corner_uv.copy()
        core.pack_uv_by_height(out, *mesh_arrays, vertex_height=height, submesh_of_vertex=sub, submesh_count=count)
        return out

    return {
        "bake": (bake, corner_verts, 2**30),
        "bake-faces": (bake, face_starts, 2**30),
        "bake-edges": (bake, edges, -7),
        "submeshes": (lambda: core.find_submeshes(*mesh_arrays)[0], corner_verts, 2**30),
        "validate": (lambda: core.validate_mesh(*mesh_arrays), corner_verts, 2**30),
        "face-offsets": (lambda: core.face_offsets_from_corner_edges(corner_verts, corner_edges, edges, n, 5),
                         corner_edges, 2**30),
        "across": (lambda: core.select_linked_across(positions, selected, sub, count, 1e-3)[0], sub, 2**30),
        "across-nan": (lambda: core.select_linked_across(positions, selected, sub, count, 1e-3)[0], positions, np.nan),
        "linked": (lambda: core.select_linked_submeshes(selected, sub, count)[0], sub, 2**30),
        "dedup": (lambda: core.find_duplicate_submeshes(positions, sub, count)[0], sub, 2**30),
        "merge": (lambda: core.merge_targets(positions, sub, count, distance=1e-3)[0], sub, -2**30),
        "merge-passes": (lambda: core.merge_passes(positions, sub, count, distance=1e-3)[0], sub, 2**30),
        "weld": (lambda: core.weld(*mesh_arrays, target)["corner_verts"], target, 2**30),
        "remove": (lambda: core.remove_vertices(*mesh_arrays, remove, corner_edges)["corner_verts"], corner_verts,
                   2**30),
        "pack-uv": (pack_uv, sub, 2**30),
        "corner-uv": (corner_uv_call, corner_verts, 2**30),
        "pairs-nan": (lambda: core.find_close_pairs(positions, 1e-3), positions, np.nan),
    }


def arrays_of(result):
    """A result (array, tuple, dict, dataclass, number or None) as its list of arrays."""
    if dataclasses.is_dataclass(result):
        result = [v for v in vars(result).values() if isinstance(v, np.ndarray)]
    elif isinstance(result, dict):
        result = [result[k] for k in sorted(result)]
    elif not isinstance(result, (tuple, list)):
        result = [result]
    return [np.asarray(a) for a in result]


def same(got, expected, case):
    if case in CHECKS_NOTHING:
        return all(a.shape == b.shape and a.dtype == b.dtype for a, b in zip(got, expected))
    return len(got) == len(expected) and all(np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
                                             for a, b in zip(got, expected))


def main(case, calls):
    call, spoiled, bad_value = cases(case)
    expected = arrays_of(call())
    good = spoiled.copy()
    rows = np.arange(0, len(spoiled), 7)
    stop = threading.Event()

    def writer():
        while not stop.is_set():
            spoiled[rows] = bad_value
            spoiled[rows] = good[rows]

    sys.setswitchinterval(1e-5)  # the writer also runs between the Python lines of a call
    thread = threading.Thread(target=writer)
    thread.start()
    results = errors = 0
    try:
        for _ in range(calls):
            try:
                got = arrays_of(call())
            except ValueError:
                errors += 1
                continue
            results += 1
            if not same(got, expected, case):
                print(case, "wrong result", flush=True)
                sys.exit(3)
    finally:
        stop.set()
        thread.join()
    print(case, results, errors, flush=True)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))

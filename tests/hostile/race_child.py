"""Child of tests/test_hostile_core2.py: one core function called again and again while another
Python thread keeps writing out-of-range indices (or NaN) into its input arrays and putting the
valid values back. The core runs without the GIL, so the writer runs during the call.

    python race_child.py CASE CALLS

Prints 'CASE results errors' (calls that returned, calls refused with ValueError); a returned
result must equal the one computed from the untouched arrays, or the child exits 3. Any other
exception propagates (exit 1); a crash shows as death by a signal."""
import sys
import threading

import numpy as np

from boxmarch import core, scenes


def mesh(count=3000):
    arrays, *_ = scenes.random_boxes(count, seed=4, spread=20.0)
    return [np.ascontiguousarray(a) for a in arrays]


def cases():
    """CASE -> (call, the array the writer spoils, the spoiling value, what a result must equal)."""
    positions, edges, face_starts, face_sizes, corner_verts = mesh()
    sub, count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    n = len(positions)
    selected = np.zeros(n, np.uint8)
    selected[::50] = 1
    target = np.arange(n, dtype=np.int32)
    corner_uv = np.zeros((len(corner_verts), 2), np.float32)
    result = core.bake(positions, edges, face_starts, face_sizes, corner_verts)

    def bake():
        r = core.bake(positions, edges, face_starts, face_sizes, corner_verts)
        return r.offsets, r.quaternions

    def corner_uv_call():
        out = np.zeros_like(corner_uv)
        core.corner_quaternion_uv(out, 0, corner_verts, result, write_all=True)
        return out

    return {
        "bake": (bake, corner_verts, 2**30),
        "bake-faces": (bake, face_starts, 2**30),
        "bake-edges": (bake, edges, -7),
        "submeshes": (lambda: core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)[0],
                      corner_verts, 2**30),
        "across": (lambda: core.select_linked_across(positions, selected, sub, count, 1e-3)[0], sub, 2**30),
        "across-nan": (lambda: core.select_linked_across(positions, selected, sub, count, 1e-3)[0], positions, np.nan),
        "dedup": (lambda: core.find_duplicate_submeshes(positions, sub, count)[0], sub, 2**30),
        "merge": (lambda: core.merge_targets(positions, sub, count, distance=1e-3)[0], sub, -2**30),
        "weld": (lambda: core.weld(positions, edges, face_starts, face_sizes, corner_verts, target)["corner_verts"],
                 target, 2**30),
        "corner-uv": (corner_uv_call, corner_verts, 2**30),
        "pairs-nan": (lambda: core.find_close_pairs(positions, 1e-3), positions, np.nan),
    }


def main(case, calls):
    call, spoiled, bad_value = cases()[case]
    expected = call()
    good = spoiled.copy()
    rows = np.arange(0, len(spoiled), 7)
    stop = threading.Event()

    def writer():
        while not stop.is_set():
            spoiled[rows] = bad_value
            spoiled[rows] = good[rows]

    thread = threading.Thread(target=writer)
    thread.start()
    results = errors = 0
    try:
        for _ in range(calls):
            try:
                got = call()
            except ValueError:
                errors += 1
                continue
            results += 1
            pairs = zip(got, expected) if isinstance(got, tuple) else [(got, expected)]
            if not all(np.array_equal(a, b) for a, b in pairs):
                print(case, "wrong result", flush=True)
                sys.exit(3)
    finally:
        stop.set()
        thread.join()
    print(case, results, errors, flush=True)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))

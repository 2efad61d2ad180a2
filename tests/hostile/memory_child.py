# Run by tests/test_hostile_core.py under an address-space limit (ulimit -v): each case prints
# "<case> ok" or "<case> MemoryError"; anything else (an abort) fails the test.
import sys

import numpy as np

from boxmarch import core
case = sys.argv[1]
def outcome(fn):
    try:
        fn()
        print(case, "ok")
    except MemoryError:
        print(case, "MemoryError")
if case == "pairs":
    pos = np.zeros((60000, 3), np.float32)
    outcome(lambda: core.find_close_pairs(pos, 1.0, threads=4))
if case == "merge":
    n = int(sys.argv[2])
    pos = np.zeros((n, 3), np.float32)
    outcome(lambda: core.merge_targets(pos, np.zeros(n, np.int32), 1, distance=1e-3, threads=4))
if case == "across":
    n = int(sys.argv[2])
    pos = np.random.default_rng(0).random((n, 3), dtype=np.float32)
    sub = (np.arange(n) // 8).astype(np.int32)
    sel = np.zeros(n, np.uint8)
    sel[0] = 1
    outcome(lambda: core.select_linked_across(pos, sel, sub, n // 8, epsilon=10.0, threads=4))
def boxes(n):
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float32)
    quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]], np.int32)
    pos = (corners[None] + np.arange(n, dtype=np.float32)[:, None, None] * 2).reshape(-1, 3)
    cv = (quads[None] + 8 * np.arange(n, dtype=np.int32)[:, None, None]).reshape(-1)
    e = np.array([[0, 1], [1, 3], [3, 2], [2, 0], [4, 5], [5, 7], [7, 6], [6, 4], [0, 4], [1, 5], [2, 6], [3, 7]], np.int32)
    edges = (e[None] + 8 * np.arange(n, dtype=np.int32)[:, None, None]).reshape(-1, 2)
    fs = np.arange(6 * n, dtype=np.int32) * 4
    return pos, edges, fs, np.full(6 * n, 4, np.int32), cv
if case == "bake":
    arrays = boxes(int(sys.argv[2]))
    outcome(lambda: core.bake(*arrays, threads=4))
if case == "render":
    n = int(sys.argv[2])
    o = np.random.default_rng(1).random((n, 3)).astype(np.float32) * 10
    q = np.tile(np.array([0, 0, 0, 1], np.float32), (n, 1))
    h = np.full((n, 3), 0.1, np.float32)
    m = np.eye(4)
    m[2, 3] = -30
    outcome(lambda: core.render_boxes(o, q, h, m, m, 64, 64, threads=4))

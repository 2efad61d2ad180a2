"""Synthetic geometry for the demo, the benchmarks and the tests: boxes as flat mesh arrays."""
from __future__ import annotations

import numpy as np

from .formats.layouts import quaternion_matrices

# Unit cube corners (x, y, z in {-0.5, 0.5}), vertex i has bits (x, y, z) = (i >> 2, i >> 1, i) & 1.
_CORNERS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
# Outward-wound quads: -x, +x, -y, +y, -z, +z.
_QUADS = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
_EDGES = np.array([[0, 1], [1, 3], [3, 2], [2, 0], [4, 5], [5, 7], [7, 6], [6, 4],
                   [0, 4], [1, 5], [2, 6], [3, 7]])


def random_rotations(count: int, rng: np.random.Generator) -> np.ndarray:
    """(count, 3, 3) uniformly random rotation matrices."""
    q = rng.normal(size=(count, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return quaternion_matrices(q)


def box_arrays(centres, sizes, rotations):
    """Mesh arrays of boxes: box i is the unit cube scaled by sizes[i], turned by rotations[i]
    (3x3) and moved to centres[i]. Returns (positions float32 (8n, 3), edges int32 (12n, 2),
    face_starts, face_sizes int32 (6n,), corner_verts int32 (24n,)). Positions are computed in
    float64 and rounded once to float32, as Blender stores them."""
    centres = np.asarray(centres, np.float64).reshape(-1, 3)
    n = len(centres)
    sizes = np.broadcast_to(np.asarray(sizes, np.float64), (n, 3))
    rotations = np.broadcast_to(np.asarray(rotations, np.float64), (n, 3, 3))
    local = _CORNERS[None, :, :] * sizes[:, None, :]
    positions = np.einsum("nij,nkj->nki", rotations, local) + centres[:, None, :]
    first = 8 * np.arange(n, dtype=np.int64)[:, None, None]
    corner_verts = (_QUADS[None] + first).reshape(-1).astype(np.int32)
    edges = (_EDGES[None] + first).reshape(-1, 2).astype(np.int32)
    face_starts = np.arange(0, 24 * n, 4, dtype=np.int32)
    face_sizes = np.full(6 * n, 4, np.int32)
    return positions.reshape(-1, 3).astype(np.float32), edges, face_starts, face_sizes, corner_verts


def random_boxes(count: int, seed: int = 0, size_range=(0.05, 2.0), spread=100.0):
    """``count`` boxes of random sizes and rotations scattered in a cube of side 2 * spread.
    Returns (arrays, centres float64 (n, 3), sizes (n, 3), rotations (n, 3, 3))."""
    rng = np.random.default_rng(seed)
    sizes = rng.uniform(*size_range, (count, 3))
    rotations = random_rotations(count, rng)
    centres = rng.uniform(-spread, spread, (count, 3))
    return box_arrays(centres, sizes, rotations), centres, sizes, rotations

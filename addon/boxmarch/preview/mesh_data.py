"""What the preview draws from a baked mesh, read through mesh_io."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import core, mesh_io


NotBakedError = mesh_io.NotBakedError  # the preview's name for it (draw.py, tests)


@dataclass
class BakedMesh:
    positions: np.ndarray        # float32 (N, 3) object space
    offsets: np.ndarray          # float32 (N, 4) BoxOffset as the GPU reads it (raw bytes / 255)
    quaternions: np.ndarray      # float32 (N, 4) per vertex
    half_extents: np.ndarray     # float32 (N, 3) the box of each vertex's submesh
    triangles: np.ndarray        # int32 (T, 3) vertex indices
    edges: np.ndarray            # int32 (E, 2)
    origins: np.ndarray          # float32 (S, 3) per submesh, object space
    box_quaternions: np.ndarray  # float32 (S, 4)
    box_half_extents: np.ndarray  # float32 (S, 3)


def read_baked(mesh) -> BakedMesh:
    """Everything the preview draws from, per vertex. Raises NotBakedError when a layer is missing."""
    positions = mesh_io.read_positions(mesh)
    edges, face_starts, face_sizes, corner_verts = mesh_io.read_topology(mesh)
    layers = mesh_io.read_baked_layers(mesh, corner_verts)
    n = len(positions)
    colour, quaternions = layers.shader_offsets(), layers.vertex_quaternions()
    if n and np.any(colour[:, 3] <= 0):
        raise NotBakedError(f"mesh '{mesh.name}' has BoxOffset alpha 0: bake it again")
    submesh_of_vertex, _count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    origins, box_q, box_half = core.boxes_from_bake(positions, colour, quaternions, submesh_of_vertex)
    return BakedMesh(positions=positions, offsets=colour, quaternions=quaternions,
                     half_extents=box_half[submesh_of_vertex], triangles=mesh_io.read_triangles(mesh), edges=edges,
                     origins=origins, box_quaternions=box_q, box_half_extents=box_half)


def read_triangles(mesh):
    """(positions float32 (N, 3), triangles int32 (T, 3) vertex indices) of any mesh."""
    return mesh_io.read_positions(mesh), mesh_io.read_triangles(mesh)


def vector_lines(baked: BakedMesh):
    """The decoded-vector overlay (the seed's "Decode vertex vectors" script) as line pairs,
    float32 (2N, 3) each: from every vertex along the raw decoded f, and along f rotated by q,
    which ends at the vertex's submesh origin."""
    f = core.decode_offsets(baked.offsets)
    raw = baked.positions + f
    rotated = baked.positions + core.rotate_vector(f, baked.quaternions)
    return tuple(np.stack([baked.positions, tips.astype(np.float32)], axis=1).reshape(-1, 3)
                 for tips in (raw, rotated))

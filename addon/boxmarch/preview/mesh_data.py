"""Reads a baked mesh for the preview (the preview's side of mesh_io: foreach_get only) and turns it
into the channels of an engine layout (boxmarch/layouts.py), as the preview shader reads them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import core, layouts, mesh_io


class NotBakedError(ValueError):
    """The mesh lacks the baked layers; the message says which."""


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
    submesh_of_vertex: np.ndarray  # int32 (N,) the box number of each vertex


def read_baked(mesh) -> BakedMesh:
    """Everything the preview draws from, per vertex. Raises NotBakedError when a layer is missing."""
    attr = mesh.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE)
    missing = [name for name in (mesh_io.QUAT_XY_UV, mesh_io.QUAT_ZW_UV) if name not in mesh.uv_layers]
    if attr is None or missing:
        raise NotBakedError(f"mesh '{mesh.name}' is not baked (missing {', '.join(([mesh_io.OFFSET_ATTRIBUTE] if attr is None else []) + missing)})")
    positions = mesh_io.read_positions(mesh)
    edges, face_starts, face_sizes, corner_verts = mesh_io.read_topology(mesh)
    n = len(positions)
    count = n if attr.domain == "POINT" else len(corner_verts)
    colour = np.empty(count * 4, np.float32)
    attr.data.foreach_get("color" if attr.data_type == "FLOAT_COLOR" else "color_srgb", colour)
    colour = colour.reshape(-1, 4)
    if attr.domain != "POINT":
        colour = core.vertex_values_from_corners(colour, corner_verts, n)
    corner_q = np.concatenate([mesh_io._read_uv(mesh, name, len(corner_verts))
                               for name in (mesh_io.QUAT_XY_UV, mesh_io.QUAT_ZW_UV)], axis=1)
    quaternions = core.vertex_values_from_corners(corner_q, corner_verts, n)
    if n and np.any(colour[:, 3] <= 0):
        raise NotBakedError(f"mesh '{mesh.name}' has BoxOffset alpha 0: bake it again")
    submesh_of_vertex, _count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    origins, box_q, box_half = core.boxes_from_bake(positions, colour, quaternions, submesh_of_vertex)
    return BakedMesh(positions=positions, offsets=colour, quaternions=quaternions,
                     half_extents=box_half[submesh_of_vertex], triangles=_triangles(mesh), edges=edges,
                     origins=origins, box_quaternions=box_q, box_half_extents=box_half,
                     submesh_of_vertex=submesh_of_vertex)


def _triangles(mesh) -> np.ndarray:
    """int32 (T, 3) vertex indices of the mesh's triangulation."""
    mesh.calc_loop_triangles()
    triangles = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    return triangles.reshape(-1, 3)


def read_triangles(mesh):
    """(positions float32 (N, 3), triangles int32 (T, 3) vertex indices) of any mesh."""
    return mesh_io.read_positions(mesh), _triangles(mesh)


def box_data(baked: BakedMesh) -> layouts.BoxData:
    """The bake's per-vertex box data in Blender's object frame, from which every layout's
    channels are made (as the export makes them in its target's frame)."""
    return layouts.BoxData(quaternions=baked.quaternions.astype(np.float64),
                           offsets=core.decode_offsets(baked.offsets).astype(np.float64),
                           half_extents=baked.half_extents.astype(np.float64),
                           index=baked.submesh_of_vertex.astype(np.int64), classic_rgba=baked.offsets,
                           box_half_extents=baked.box_half_extents.astype(np.float64))


def layout_inputs(layout: str, baked: BakedMesh) -> dict[str, np.ndarray]:
    """float32 per-vertex inputs of the preview shader for ``layout`` (sources.VERTEX_INPUTS):
    the layout's channels as layouts.channels() writes them for export, and ch_half where the
    layout has no per-vertex half-extents (CLASSIC: the bake's, as the preview always drew them;
    NORMAL_COLOR: its box table read at each vertex's stored index, as an engine samples it)."""
    channels = layouts.channels(layout, box_data(baked))
    table = channels.pop("TABLE", None)
    inputs = {"pos": baked.positions}
    inputs.update({"ch_" + name.lower(): values for name, values in channels.items()})
    if layout == "CLASSIC":
        inputs["ch_half"] = baked.half_extents.astype(np.float32)
    elif table is not None:
        inputs["ch_half"] = table[np.rint(channels["COLOR"][:, 3]).astype(np.int64), :3]
    return inputs


def frame_axes(quaternions) -> np.ndarray:
    """float64 (N, 3, 3) box frames of unit quaternions (N, 4): columns the local x, y, z axes."""
    axis_x, axis_z = layouts.frame_axes(quaternions)
    return np.stack([axis_x, np.cross(axis_z, axis_x), axis_z], axis=2)


def vector_lines(positions, offsets, axes):
    """The decoded-vector overlay (the seed's "Decode vertex vectors" script) as line pairs,
    float32 (2N, 3) each: from every vertex along the raw decoded f (box-local, (N, 3)), and along
    f turned by the vertex's frame ``axes`` ((N, 3, 3), columns the local axes), which ends at the
    vertex's submesh origin when the frame is right."""
    positions = np.asarray(positions, np.float64)
    raw = positions + offsets
    rotated = positions + np.einsum("nij,nj->ni", axes, offsets)
    return tuple(np.stack([positions, tips], axis=1).reshape(-1, 3).astype(np.float32) for tips in (raw, rotated))

"""What the preview draws from a baked mesh, read through mesh_io, turned into the channels of an
engine layout (boxmarch/formats/layouts.py) as the preview shader reads them."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import core, mesh_io
from ..formats import layouts
from ..formats import transforms


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
    submesh_of_vertex: np.ndarray  # int32 (N,) the box number of each vertex
    box_layers: mesh_io.BoxLayers | None = None  # per-box parameters and parents (None: baked without)
    outward: bool = False        # every box closed and wound outward (closed_outward)
    sealed: np.ndarray | None = None  # bool (S,) each box's triangles are its whole surface (sealed_boxes)


def read_baked(mesh) -> BakedMesh:
    """Everything the preview draws from, per vertex. Raises NotBakedError when a layer is missing."""
    positions = mesh_io.read_positions(mesh)
    edges, face_starts, face_sizes, corner_verts = mesh_io.read_topology(mesh)
    layers = mesh_io.read_baked_layers(mesh, corner_verts)
    n = len(positions)
    colour, quaternions = layers.shader_offsets(), layers.vertex_quaternions()
    if n and np.any(colour[:, 3] <= 0):
        raise NotBakedError(f"mesh '{mesh.name}' has BoxOffset alpha 0: bake it again")
    submesh_of_vertex, count = core.find_submeshes(positions, edges, face_starts, face_sizes, corner_verts)
    triangles = mesh_io.read_triangles(mesh)
    origins, box_q, box_half = core.boxes_from_bake(positions, colour, quaternions, submesh_of_vertex)
    return BakedMesh(positions=positions, offsets=colour, quaternions=quaternions,
                     half_extents=box_half[submesh_of_vertex], triangles=triangles, edges=edges,
                     origins=origins, box_quaternions=box_q, box_half_extents=box_half,
                     submesh_of_vertex=submesh_of_vertex,
                     box_layers=mesh_io.read_box_layers(mesh, submesh_of_vertex, count),
                     outward=closed_outward(positions, triangles, origins, submesh_of_vertex),
                     sealed=sealed_boxes(colour, box_half[submesh_of_vertex], triangles, submesh_of_vertex, len(origins)))


# How many of float32's steps (at the farthest coordinate of its box's vertices) every edge of a box's
# triangles must span for its back faces to be culled: a box drawn from vertices rounded by a
# sizeable share of its size may face the rasteriser one way and its box-local ray the other (cut
# battery seed 940: boxes 1.8e-5 across, 511 units out, 1 pixel emptied by culling).
CULL_MIN_STEPS = 256.0


def closed_outward(positions, triangles, origins, submesh_of_vertex) -> bool:
    """Whether every box's triangles close it and face outward: each directed edge once and its
    reverse once (closed, consistently wound), each box's signed volume about its origin
    positive, and every edge at least CULL_MIN_STEPS float32 steps of its box's farthest
    coordinate long. Then a box's back faces are its far side, and the preview may cull them."""
    triangles = np.asarray(triangles, np.int64)
    if not len(triangles):
        return False
    corners = positions[triangles].astype(np.float64)  # (T, 3 corners, 3)
    edge = np.linalg.norm(np.roll(corners, -1, axis=1) - corners, axis=2).min(axis=1)
    box_of_triangle = submesh_of_vertex[triangles[:, 0]]
    farthest = np.zeros(len(origins))
    np.maximum.at(farthest, box_of_triangle, np.abs(corners).max(axis=(1, 2)))
    shortest = np.full(len(origins), np.inf)
    np.minimum.at(shortest, box_of_triangle, edge)
    if np.any(shortest < CULL_MIN_STEPS * np.spacing(farthest.astype(np.float32))):
        return False
    directed = np.stack([triangles, np.roll(triangles, -1, axis=1)], -1).reshape(-1, 2)
    key = directed[:, 0] * len(positions) + directed[:, 1]
    reverse = directed[:, 1] * len(positions) + directed[:, 0]
    if len(np.unique(key)) != len(key) or not np.all(np.isin(reverse, key)):
        return False
    box = submesh_of_vertex[triangles[:, 0]]
    a, b, c = (positions[triangles[:, k]].astype(np.float64) - origins[box] for k in range(3))
    volume = np.bincount(box, np.einsum("ij,ij->i", a, np.cross(b, c)), minlength=len(origins))
    return bool(np.all(volume > 0.0))


def wound_outward(positions, triangles, origins, submesh_of_vertex) -> np.ndarray:
    """``triangles`` (T, 3), their type kept (a GPU index buffer takes int32), with each whose
    object-space normal (counter-clockwise in front) points toward its box's origin turned over,
    so the pre-pass draws its occluders' front faces only, whatever the mesh's winding
    (docs/PREVIEW.md, "Hidden boxes": a back face seen nearly edge-on, its vertices snapped, may
    tilt its depth plane nearer than its occluder's front face on a pixel that face's snapped edge
    leaves). Meant for a sealed box's triangles, each on one face (sealed_boxes); a wrong call (a
    flat box's rounding) culls a front face and keeps the back one behind it, which hides less,
    never more."""
    triangles = np.array(triangles).reshape(-1, 3)
    if not len(triangles):
        return triangles
    a, b, c = (positions[triangles[:, k]].astype(np.float64) for k in range(3))
    outward = (a + b + c) / 3.0 - origins[submesh_of_vertex[triangles[:, 0]]]
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), outward) < 0.0
    triangles[inward] = triangles[inward][:, [0, 2, 1]]
    return triangles


# How far (a share of a box's largest half-extent) a box's triangle may lie inside a face of its
# box and count as on it (sealed_boxes): within the margin by which bm_occluder_half pulls the
# occluders in (box_params.glsl), so the faces still cover every occluder.
SEALED_TOLERANCE = 1e-3


def sealed_boxes(offsets, half_extents, triangles, submesh_of_vertex, box_count: int) -> np.ndarray:
    """bool (S,): whether each box's triangles are the whole surface of its box, whichever way
    they are wound: every edge of them shared by exactly two, and each on one face of the box (its
    corners' box-local positions -f, ``offsets`` as core.decode_offsets reads them, within
    SEALED_TOLERANCE of the largest of ``half_extents`` (N, 3, per vertex) of that face's plane).
    Only such a box is drawn wherever its shape may be seen, so only its occluders are sure to lie
    behind what the box draws (docs/PREVIEW.md, "Hidden boxes"): an open box, or a modelled shape
    smaller than its box, would hide what is seen past it."""
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    box = np.asarray(submesh_of_vertex, np.int64)[triangles[:, 0]]
    sealed = np.bincount(box, minlength=box_count) > 0
    if not len(triangles):
        return sealed
    corner = -core.decode_offsets(offsets)[triangles]  # (T, 3 corners, 3 axes) box-local
    half = np.asarray(half_extents, np.float64)[triangles[:, 0]]  # (T, 3)
    slack = half - SEALED_TOLERANCE * half.max(axis=1, keepdims=True)
    on_face = ((corner >= slack[:, None]).all(axis=1) | (corner <= -slack[:, None]).all(axis=1)).any(axis=1)
    edges = np.sort(np.stack([triangles, np.roll(triangles, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    _unique, where, uses = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    closed = (uses[where.reshape(-1)] == 2).reshape(-1, 3).all(axis=1)
    sealed &= np.bincount(box, weights=~(on_face & closed), minlength=box_count) == 0
    return sealed


def box_data_in_object_frame(baked: BakedMesh) -> layouts.BoxData:
    """The bake's per-vertex box data in Blender's object frame, from which every layout's
    channels are made (as the export makes them in its target's frame)."""
    return layouts.BoxData(quaternions=baked.quaternions.astype(np.float64),
                           offsets=core.decode_offsets(baked.offsets).astype(np.float64),
                           half_extents=baked.half_extents.astype(np.float64),
                           index=baked.submesh_of_vertex.astype(np.int64), classic_rgba=baked.offsets,
                           box_half_extents=baked.box_half_extents.astype(np.float64),
                           box_origins=baked.origins.astype(np.float64), box_quaternions=baked.box_quaternions,
                           **({} if baked.box_layers is None else {
                               "box_params": baked.box_layers.params, "box_parent": baked.box_layers.parent,
                               "box_depth": baked.box_layers.depth}))


def layout_inputs(layout: str, baked: BakedMesh) -> dict[str, np.ndarray]:
    """float32 per-vertex inputs of the preview shader for ``layout`` (shader_sources.VERTEX_INPUTS):
    the layout's channels as layouts.channels() writes them for export, and ch_half where the
    layout has no per-vertex half-extents (CLASSIC: the bake's, as the preview always drew them;
    NORMAL_COLOR: its box table read at each vertex's stored index, as an engine samples it)."""
    spec = layouts.layout_named(layout)
    channels = layouts.channels(layout, box_data_in_object_frame(baked))
    table = channels.pop("TABLE", None)
    params = box_params_input(layout, channels, table)
    for name in spec.param_channels:  # per-box values: not inputs of the frame's decode
        del channels[name]
    inputs = {"pos": baked.positions}
    inputs.update({"ch_" + name.lower(): values for name, values in channels.items()})
    if not spec.has_table:
        inputs["ch_half"] = baked.half_extents.astype(np.float32)
    elif not spec.half_extents_per_vertex:
        inputs["ch_half"] = table[_stored_index(spec, channels), 0, :3]
    inputs["ch_params"] = params
    inputs.update(parent_inputs(baked))
    return inputs


def parent_inputs(baked: BakedMesh) -> dict[str, np.ndarray]:
    """float32 (N, 4) per vertex, its box's parent in the box's own local coordinates (the
    preview's PER_BOX_BLEND, shaders/glsl/box_params.glsl): ch_parent_origin (the parent's
    origin, 0), ch_parent_q (the parent's frame relative to the box's), ch_parent_half (the
    parent's half-extents and shape id; (-1, -1, -1, 0) for a root)."""
    boxes = len(baked.origins)
    layers = baked.box_layers
    parent = np.full(boxes, -1) if layers is None else layers.parent.astype(np.int64)
    shapes = np.zeros(boxes) if layers is None else layers.params[:, 0]
    has = parent >= 0
    other = np.where(has, parent, np.arange(boxes))
    frames = layouts.quaternion_matrices(baked.box_quaternions)
    relative = np.einsum("nji,njk->nik", frames, frames[other])  # R_box^T R_parent
    origin = np.einsum("nji,nj->ni", frames, baked.origins[other].astype(np.float64) - baked.origins)
    half = np.where(has[:, None], np.concatenate([baked.box_half_extents[other], shapes[other, None]], 1),
                    np.array([-1.0, -1.0, -1.0, 0.0]))
    per_box = {"ch_parent_origin": np.concatenate([origin, np.zeros((boxes, 1))], 1),
               "ch_parent_q": transforms.matrix_quaternions(relative), "ch_parent_half": half}
    return {name: values[baked.submesh_of_vertex].astype(np.float32) for name, values in per_box.items()}


def box_params_input(layout: str, channels: dict, table) -> np.ndarray:
    """float32 (N, 4) each vertex's box parameters as an engine reads them from ``layout``
    (docs/ENGINES.md): the (shape, material) and (random, user) channels, or the box table's
    plane 1 at the vertex's index where the layout has no such channel."""
    spec = layouts.layout_named(layout)
    held = {name: channels[channel][:, k] for channel, names in spec.param_channels.items()
            for k, name in enumerate(names)}
    names = ("shape", "material", "random", "user")
    if all(name in held for name in names):
        return np.stack([held[name] for name in names], 1).astype(np.float32)
    params = table[_stored_index(spec, channels), 1].copy()
    for k, name in enumerate(names):
        if name in held:
            params[:, k] = held[name]
    return params


def _stored_index(spec: layouts.Layout, channels: dict) -> np.ndarray:
    """Each vertex's box number as the layout stores it (a float channel), rounded as an engine reads it."""
    return np.rint(layouts.component(channels, spec.quantities["index"]["channels"][0])).astype(np.int64)


def vector_lines(positions, offsets, axes):
    """The decoded-vector overlay (the seed's "Decode vertex vectors" script) as line pairs,
    float32 (2N, 3) each: from every vertex along the raw decoded f (box-local, (N, 3)), and along
    f turned by the vertex's frame ``axes`` ((N, 3, 3), columns the local axes), which ends at the
    vertex's submesh origin when the frame is right."""
    positions = np.asarray(positions, np.float64)
    raw = positions + offsets
    rotated = positions + np.einsum("nij,nj->ni", axes, offsets)
    return tuple(np.stack([positions, tips], axis=1).reshape(-1, 3).astype(np.float32) for tips in (raw, rotated))


# The eight view octants: the signs (x, y, z) of an object-space view direction.
OCTANT_DIAGONALS = np.array([[1.0 if octant & bit else -1.0 for bit in (1, 2, 4)] for octant in range(8)])


def view_octant(object_to_view) -> int:
    """The octant (0..7, bit k set where axis k is positive) of the object-space direction the
    camera looks along."""
    direction = -np.asarray(object_to_view, np.float64)[2, :3]
    return int(sum(1 << k for k in range(3) if direction[k] >= 0.0))


def octant_triangles(baked: BakedMesh, octant: int) -> np.ndarray:
    """The triangles (int32 (T, 3)) box by box, front to back for a view along ``octant``'s
    diagonal: boxes sorted by their origin along it (core.front_to_back), each box's triangles
    in their own order. Near enough to front to back for any view in the octant for early depth
    testing to skip most hidden marches (bench/bench_gpu_cost.py)."""
    order = core.front_to_back(baked.origins, np.append(OCTANT_DIAGONALS[octant], 0.0))
    rank = np.empty(len(order), np.int64)
    rank[order] = np.arange(len(order))
    box_of_triangle = baked.submesh_of_vertex[baked.triangles[:, 0]]
    return np.ascontiguousarray(baked.triangles[np.argsort(rank[box_of_triangle], kind="stable")])


def layers_over_view(origins, half_extents, object_to_clip, width: int, height: int) -> float:
    """About how many layers of boxes cover the view: the bounding spheres of the boxes in the
    view frustum projected (each at most the view's area; none behind the eye), their areas
    summed over the view's."""
    origins = np.asarray(origins, np.float64)
    clip = origins @ object_to_clip.T[:3] + object_to_clip.T[3]
    radius = np.linalg.norm(np.asarray(half_extents, np.float64), axis=1)
    rows = np.linalg.norm(object_to_clip[:3, :3], axis=1)  # clip units per object unit, x, y and z
    w = clip[:, 3] if np.any(object_to_clip[3, :3]) else np.ones(len(clip))
    inside = ((np.abs(clip[:, 0]) - radius * rows[0] <= w) & (np.abs(clip[:, 1]) - radius * rows[1] <= w)
              & (w > 0.0))
    pixels = np.pi * (radius[inside] * rows[1] * 0.5 * height / w[inside]) ** 2
    return float(np.minimum(pixels, width * height).sum() / (width * height))

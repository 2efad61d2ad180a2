"""The submesh tools as jobs: select linked submeshes, select linked across, delete duplicate
submeshes, merge by distance per submesh, pack UVs by Z. The operators (operators/tools.py) and
the command line (cli.py) both run them through ``run_tool``.

A tool is a small dataclass holding its options; ``plan`` reads what it needs, asks the core, and
either writes the result (a rebuilt mesh, a selection, UVs) or leaves a ``BlenderEdit``: Blender's
own edit-mode operators on a planned selection, run once the objects are back in Edit Mode.
Every mesh is read and checked before any is changed; bad input raises ToolInputError."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np

from . import core, core_tools, edit_mode, mesh_io


class ToolInputError(ValueError):
    """A mesh the tool cannot work on; the message says why. Nothing was changed."""


@dataclass
class ToolMesh:
    """One object's mesh as the tools see it: its arrays and submeshes, read in Object Mode."""

    ob: object
    positions: np.ndarray
    edges: np.ndarray
    face_starts: np.ndarray
    face_sizes: np.ndarray
    corner_verts: np.ndarray
    submesh_of_vertex: np.ndarray
    submesh_count: int
    edit: bool  # the tool runs in Edit Mode: the selection says which submeshes to work on

    @property
    def topology(self):
        return self.positions, self.edges, self.face_starts, self.face_sizes, self.corner_verts

    def chosen_submeshes(self) -> np.ndarray:
        """uint8 per submesh: touched by the vertex selection in Edit Mode, all in Object Mode."""
        if not self.edit:
            return np.ones(self.submesh_count, np.uint8)
        chosen = np.zeros(self.submesh_count, np.uint8)
        chosen[self.submesh_of_vertex[mesh_io.read_vertex_selection(self.ob.data)]] = 1
        return chosen


def read_tool_mesh(ob, edit: bool, need_faces: bool = False) -> ToolMesh:
    """The object's mesh arrays and submeshes. Raises ToolInputError (naming the mesh) when the
    mesh is linked, empty, without faces (if ``need_faces``) or holds NaN/infinite coordinates."""
    mesh = ob.data
    if mesh.library is not None:
        raise ToolInputError(f"mesh '{mesh.name}' is linked from a library and cannot be changed")
    if len(mesh.vertices) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' is empty")
    if need_faces and len(mesh.polygons) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' has no faces")
    positions = mesh_io.read_positions(mesh)
    topology = mesh_io.read_topology(mesh)
    try:
        core.validate_mesh(positions, *topology)
    except ValueError as error:
        raise ToolInputError(f"mesh '{mesh.name}': {error}") from None
    ids, count = core.find_submeshes(positions, *topology)
    return ToolMesh(ob, positions, *topology, ids, count, edit)


@dataclass
class ToolOutcome:
    """What a tool's plan did, and what is left to do once back in Edit Mode."""

    summary: str  # the report; a "{removed}" in it is the vertices the Blender edit removed
    blender_edit: edit_mode.BlenderEdit | None = None
    vertices_before: int | None = None  # set when the summary counts removed vertices


Progress = Callable[[int], None]  # percent done, 0..100


def run_tool(context, tool, objects, progress: Progress | None = None) -> str:
    """Run ``tool`` on ``objects`` (mesh objects, one per mesh datablock: those in Edit Mode, or
    the selected ones in Object Mode). Returns the report line; raises ToolInputError (or
    ValueError from the core) with nothing changed."""
    progress = progress or (lambda _percent: None)
    if not objects:
        raise ToolInputError("select at least one mesh object")
    with edit_mode.object_mode(context) as edit:
        # Read and check every mesh before changing any.
        meshes = [read_tool_mesh(ob, edit, tool.need_faces) for ob in objects]
        if edit and tool.needs_vertex_selection and not any(
                mesh_io.read_vertex_selection(ob.data).any() for ob in objects):
            raise ToolInputError("no vertex is selected")
        progress(20)
        outcome = tool.plan(context, meshes, progress)
    # Blender's edit-mode operators run once the objects are back in Edit Mode.
    if outcome.blender_edit is not None:
        outcome.blender_edit.run(context, edit)
    if outcome.vertices_before is not None:
        return outcome.summary.format(removed=outcome.vertices_before - edit_mode.vertex_total(objects))
    return outcome.summary


def _grow_selection(meshes, grow) -> int:
    """Replace each mesh's visible vertex selection by what grow(selected, mesh) returns as
    (mask, submeshes selected); hidden vertices stay unselected. Returns the submeshes selected."""
    total = 0
    for m in meshes:
        hidden = mesh_io.read_hidden_vertices(m.ob.data)
        selected = mesh_io.read_vertex_selection(m.ob.data) & ~hidden
        mask, count = grow(selected, m)
        mesh_io.write_selection(m.ob.data, mask.astype(bool) & ~hidden, m.edges, m.face_starts, m.corner_verts)
        total += count
    return total


@dataclass
class SelectLinked:
    need_faces: ClassVar[bool] = False
    needs_vertex_selection: ClassVar[bool] = True

    def plan(self, context, meshes, progress) -> ToolOutcome:
        total = _grow_selection(meshes, lambda selected, m: core.select_linked_submeshes(
            selected, m.submesh_of_vertex, m.submesh_count))
        return ToolOutcome(f"Selected {total} submesh(es) in {len(meshes)} mesh(es)")


@dataclass
class SelectLinkedAcross:
    epsilon: float = 1e-4
    need_faces: ClassVar[bool] = False
    needs_vertex_selection: ClassVar[bool] = True

    def plan(self, context, meshes, progress) -> ToolOutcome:
        total = _grow_selection(meshes, lambda selected, m: core.select_linked_across(
            m.positions, selected, m.submesh_of_vertex, m.submesh_count, self.epsilon))
        return ToolOutcome(f"Selected {total} submesh(es) in {len(meshes)} mesh(es), epsilon {self.epsilon:g}")


@dataclass
class DeleteDuplicates:
    tolerance: float = core_tools.DUPLICATE_TOLERANCE
    need_faces: ClassVar[bool] = False
    needs_vertex_selection: ClassVar[bool] = True

    def plan(self, context, meshes, progress) -> ToolOutcome:
        deletes, total = [], 0
        for m in meshes:
            duplicate_of, count = core.find_duplicate_submeshes(
                m.positions, m.submesh_of_vertex, m.submesh_count, m.chosen_submeshes(), self.tolerance)
            deletes.append((duplicate_of >= 0)[m.submesh_of_vertex])
            total += count
        progress(50)
        summary = f"Deleted {total} duplicate submesh(es) in {len(meshes)} mesh(es), tolerance {self.tolerance:g}"
        if not total:
            return ToolOutcome(summary)
        if not any(mesh_io.rebuild_blocker(m.ob.data, welding=False) for m in meshes):
            # Whole submeshes go: the survivors' rows, rebuilt in one go with every attribute
            # (the selection included) carried over.
            for m, delete in zip(meshes, deletes):
                if delete.any():
                    removed = core.remove_vertices(*m.topology, delete, mesh_io.read_corner_edges(m.ob.data))
                    mesh_io.rebuild_welded(m.ob.data, m.positions, removed)
            return ToolOutcome(summary)
        plans = [edit_mode.VertexPlan(m.ob, delete, mesh_io.read_vertex_selection(m.ob.data))
                 for m, delete in zip(meshes, deletes)]
        return ToolOutcome(summary, edit_mode.delete_vertices(context, plans))


@dataclass
class MergeByDistance:
    distance: float = core_tools.MERGE_DISTANCE
    need_faces: ClassVar[bool] = False
    needs_vertex_selection: ClassVar[bool] = True

    def plan(self, context, meshes, progress) -> ToolOutcome:
        # The merge computed here and written as a rebuilt mesh (fast, Blender 4.1+), or
        # Blender's own Merge by Distance on a planned selection where a rebuild could lose
        # data or Blender's weld would do more (split or dedupe faces).
        chosen = [m.chosen_submeshes() for m in meshes]
        welds = self._welds(meshes, chosen)
        progress(50)
        if welds is not None:
            removed = 0
            for m, (merged_positions, weld, count) in zip(meshes, welds):
                if count:
                    mesh_io.rebuild_welded(m.ob.data, merged_positions, weld)
                    removed += count
            return ToolOutcome(f"Removed {removed} vertices in {len(meshes)} mesh(es), distance {self.distance:g}")

        plans, passes = [], 0
        for m, c in zip(meshes, chosen):
            pass_of_vertex, count = core.merge_passes(m.positions, m.submesh_of_vertex, m.submesh_count, c,
                                                      self.distance)
            plans.append(edit_mode.VertexPlan(m.ob, pass_of_vertex, mesh_io.read_vertex_selection(m.ob.data)))
            passes = max(passes, count)
        if not passes:
            return ToolOutcome("Removed 0 vertices: no submesh has vertices that close")
        before = sum(len(m.positions) for m in meshes)
        edit = edit_mode.merge_by_distance(context, plans, self.distance,
                                           lambda k, n: progress(50 + 50 * k // n))
        return ToolOutcome(f"Removed {{removed}} vertices in {len(meshes)} mesh(es) with Blender's merge "
                           f"({passes} pass(es)), distance {self.distance:g}", edit, vertices_before=before)

    def _welds(self, meshes, chosen):
        """(merged positions, weld, merged count) per mesh when every mesh can be rebuilt from the
        core's weld, else None (Blender's merge does the work)."""
        welds = []
        for m, c in zip(meshes, chosen):
            target, merged_positions, count = core.merge_targets(m.positions, m.submesh_of_vertex,
                                                                 m.submesh_count, c, self.distance)
            weld = None
            if count and mesh_io.rebuild_blocker(m.ob.data, welding=True) is None:
                weld = core.weld(*m.topology, target, mesh_io.read_corner_edges(m.ob.data))
            if count and (weld is None or weld["incomplete"]):
                return None
            welds.append((merged_positions, weld, count))
        return welds


def uv_map_name(mesh, requested: str) -> str:
    """The UV map to pack: ``requested`` by name, or the active one when empty. The maps the bake
    writes (mesh_io.BAKED_UV_MAPS) are refused: they hold the box frame, not texture space."""
    if len(mesh.uv_layers) == 0:
        raise ToolInputError(f"mesh '{mesh.name}' has no UV map")
    if requested and requested not in mesh.uv_layers:
        raise ToolInputError(f"mesh '{mesh.name}' has no UV map named '{requested}'")
    name = requested or (mesh.uv_layers.active.name if mesh.uv_layers.active else mesh.uv_layers[0].name)
    if name in mesh_io.BAKED_UV_MAPS:
        others = [uv.name for uv in mesh.uv_layers if uv.name not in mesh_io.BAKED_UV_MAPS]
        raise ToolInputError(
            f"mesh '{mesh.name}': the UV map '{name}'{'' if requested else ' (the active one)'} holds the baked box "
            "frame, which packing would overwrite; "
            + (f"pack the texture UV map ('{others[0]}')" if others else "make a texture UV map to pack"))
    return name


def world_heights(ob, positions) -> np.ndarray:
    """World Z of every vertex (float32), from the object's world matrix."""
    row = np.array(ob.matrix_world, np.float64)[2]
    return (positions.astype(np.float64) @ row[:3] + row[3]).astype(np.float32)


@dataclass
class PackUvByZ:
    padding: float = core_tools.PACK_UV_PADDING
    max_per_row: int = 0
    lock_overlapping: bool = False
    uv_map: str = ""
    need_faces: ClassVar[bool] = True
    needs_vertex_selection: ClassVar[bool] = False  # faces decide, and the core says when none is selected
    _parts: ClassVar[tuple] = ("positions", "edges", "face_starts", "face_sizes", "corner_verts", "ids",
                               "heights", "uv", "mask")

    def plan(self, context, meshes, progress) -> ToolOutcome:
        # All meshes pack together into one square, as Blender packs multi-object UVs.
        names = [uv_map_name(m.ob.data, self.uv_map) for m in meshes]
        joined = self._joined(meshes, names)
        if not joined["mask"].any():
            raise ToolInputError("no face is selected")
        uv = np.ascontiguousarray(joined["uv"])
        report = core.pack_uv_by_height(
            uv, joined["positions"], joined["edges"].astype(np.int32), joined["face_starts"].astype(np.int32),
            joined["face_sizes"], joined["corner_verts"].astype(np.int32), vertex_height=joined["heights"],
            submesh_of_vertex=joined["ids"].astype(np.int32), submesh_count=sum(m.submesh_count for m in meshes),
            face_mask=joined["mask"], padding=self.padding, max_per_row=self.max_per_row,
            lock_overlapping=self.lock_overlapping)
        progress(80)
        offset = 0
        for m, name in zip(meshes, names):
            mesh_io.write_uv(m.ob.data, name, uv[offset:offset + len(m.corner_verts)])
            m.ob.data.update()
            offset += len(m.corner_verts)
        return ToolOutcome(f"Packed {report['islands']} UV islands ({report['groups']} units, {report['rows']} rows) "
                           f"by Z at scale {report['scale']:.4g}")

    def _joined(self, meshes, names) -> dict:
        """The meshes' arrays end to end, indices shifted to the joined numbering."""
        parts = {key: [] for key in self._parts}
        vertices = corners = submeshes = 0
        for m, name in zip(meshes, names):
            parts["positions"].append(m.positions)
            parts["edges"].append(m.edges + vertices)
            parts["face_starts"].append(m.face_starts + corners)
            parts["face_sizes"].append(m.face_sizes)
            parts["corner_verts"].append(m.corner_verts + vertices)
            parts["ids"].append(m.submesh_of_vertex + submeshes)
            parts["heights"].append(world_heights(m.ob, m.positions))
            parts["uv"].append(mesh_io.read_uv(m.ob.data, name))
            parts["mask"].append(mesh_io.read_face_selection(m.ob.data) if m.edit
                                 else np.ones(len(m.face_starts), bool))
            vertices += len(m.positions)
            corners += len(m.corner_verts)
            submeshes += m.submesh_count
        return {key: np.concatenate(value) for key, value in parts.items()}

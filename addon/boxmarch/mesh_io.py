"""The one place that reads and writes Blender mesh data.

Everything moves through ``foreach_get``/``foreach_set`` on NumPy buffers of exactly the right
type and size; nothing loops over vertices, corners or faces in Python. Layers are always looked
up by name right before they are used: adding a layer may move the others in memory, so no
reference to a layer is held across a call that adds one.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import bpy
import numpy as np

from . import core

OFFSET_ATTRIBUTE = "BoxOffset"
QUAT_XY_UV = "BoxQuatXY"
QUAT_ZW_UV = "BoxQuatZW"
FINGERPRINT_ATTRIBUTE = ".boxmarch_fingerprint"
MAX_UV_MAPS = 8

# Colour written where nothing was baked yet: decodes to f = 0 (float) and the identity frame.
NEUTRAL_FLOAT = np.array([0.5, 0.5, 0.5, 1.0], np.float32)
NEUTRAL_BYTE = np.array([128, 128, 128, 255], np.uint8)


class BakeInputError(ValueError):
    """The mesh cannot be baked as it is; the message says why. Nothing was written."""


def new_mesh(name, positions, face_starts, face_sizes, corner_verts, edges=None):
    """A new mesh datablock holding these faces, plus ``edges`` (E, 2) when given (loose edges
    need them); Blender derives the faces' edges (and each corner's edge), as in any mesh made in
    the editor."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.asarray(positions, np.float32).reshape(-1))
    if edges is not None and len(edges):
        mesh.edges.add(len(edges))
        mesh.edges.foreach_set("vertices", np.asarray(edges, np.int32).reshape(-1))
    mesh.loops.add(len(corner_verts))
    mesh.loops.foreach_set("vertex_index", np.asarray(corner_verts, np.int32))
    mesh.polygons.add(len(face_starts))
    mesh.polygons.foreach_set("loop_start", np.asarray(face_starts, np.int32))
    if bpy.app.version < (4, 0, 0):  # 4.0 derives sizes from the starts
        mesh.polygons.foreach_set("loop_total", np.asarray(face_sizes, np.int32))
    mesh.update(calc_edges=True)
    # Blender 5.0.1 leaves the edges it derives with an INT32_2D '.select_edge' (a copy of the
    # edge layout), and RNA access to edge selection then crashes; selection layers are optional.
    select_edge = mesh.attributes.get(".select_edge")
    if select_edge is not None and select_edge.data_type != "BOOLEAN":
        mesh.attributes.remove(select_edge)
    return mesh


def _fast_attribute(mesh, name):
    """Blender 4+ keeps topology in internal attributes with contiguous storage (much faster to
    read than the per-element RNA of mesh.loops or mesh.edges); 3.x has none of them."""
    attr = mesh.attributes.get(name)
    return attr if attr is not None and name.startswith(".") else None


def read_positions(mesh) -> np.ndarray:
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    attr = mesh.attributes.get("position")
    if attr is not None and attr.data_type == "FLOAT_VECTOR" and bpy.app.version >= (4, 0, 0):
        attr.data.foreach_get("vector", positions)
    else:
        mesh.vertices.foreach_get("co", positions)
    return positions.reshape(-1, 3)


def read_topology(mesh):
    """(edges (E, 2), face_starts (F,), face_sizes (F,), corner_verts (C,)), all int32."""
    edges = np.empty(len(mesh.edges) * 2, np.int32)
    attr = _fast_attribute(mesh, ".edge_verts")
    if attr is not None:
        attr.data.foreach_get("value", edges)
    else:
        mesh.edges.foreach_get("vertices", edges)
    corner_verts = np.empty(len(mesh.loops), np.int32)
    attr = _fast_attribute(mesh, ".corner_vert")
    if attr is not None:
        attr.data.foreach_get("value", corner_verts)
    else:
        mesh.loops.foreach_get("vertex_index", corner_verts)
    edges = edges.reshape(-1, 2)
    faces = None
    attr = _fast_attribute(mesh, ".corner_edge")
    if attr is not None:
        corner_edges = np.empty(len(mesh.loops), np.int32)
        attr.data.foreach_get("value", corner_edges)
        faces = core.face_offsets_from_corner_edges(corner_verts, corner_edges, edges,
                                                    len(mesh.vertices), len(mesh.polygons))
    if faces is None:
        face_starts = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_start", face_starts)
        face_sizes = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_total", face_sizes)
        faces = face_starts, face_sizes
    return edges, faces[0], faces[1], corner_verts


def read_vertex_selection(mesh) -> np.ndarray:
    """uint8 per vertex, 1 where selected (object-mode data: leave Edit Mode first)."""
    selected = np.zeros(len(mesh.vertices), bool)
    attr = _fast_attribute(mesh, ".select_vert")
    if attr is not None:
        attr.data.foreach_get("value", selected)
    elif bpy.app.version < (4, 0, 0):
        mesh.vertices.foreach_get("select", selected)
    return selected.view(np.uint8)


def _uv_buffer_accessor(uv_layer):
    """(collection, property) for bulk UV access: uv_layer.uv/'vector' from 3.5, data/'uv' before."""
    return (uv_layer.uv, "vector") if hasattr(uv_layer, "uv") else (uv_layer.data, "uv")


def _read_uv(mesh, name, corner_count) -> np.ndarray:
    buf = np.empty(corner_count * 2, np.float32)
    collection, prop = _uv_buffer_accessor(mesh.uv_layers[name])
    collection.foreach_get(prop, buf)
    return buf.reshape(-1, 2)


def _write_uv(mesh, name, values: np.ndarray) -> None:
    # From 3.5 a UV map is a FLOAT2 attribute. Writing it through the attribute API un-shares the
    # array first; uv_layer.uv writes straight into an array a copied mesh (Shift+D) may share.
    attr = mesh.attributes.get(name)
    if attr is not None and attr.data_type == "FLOAT2":
        attr.data.foreach_set("vector", values.reshape(-1))
        return
    collection, prop = _uv_buffer_accessor(mesh.uv_layers[name])
    collection.foreach_set(prop, values.reshape(-1))


def modifier_warnings(objects, action: str = "bake") -> list:
    """One line per object whose enabled modifiers change what the viewport shows: the bake and
    the export read the mesh data (the base mesh), so the shown mesh would not decode."""
    warnings = []
    for ob in objects:
        mods = [m for m in getattr(ob, "modifiers", ()) if m.show_viewport or m.show_render]
        moving = [m.name for m in mods if m.type != "ARMATURE"]
        armature = [m.name for m in mods if m.type == "ARMATURE"]
        if moving:
            warnings.append(f"object '{ob.name}' has modifiers that move vertices ({', '.join(moving)}): "
                            f"the {action} uses the base mesh, so the mesh shown with modifiers does not decode "
                            "(apply them first)")
        if armature:
            warnings.append(f"object '{ob.name}' has an Armature modifier ({', '.join(armature)}): "
                            f"the {action} uses the rest geometry; posed boxes decode only where the pose "
                            "moves whole submeshes rigidly")
    return warnings


LAYERS_DIGEST = "_boxmarch_layers"  # mesh custom property: checksum of the stored layers


def stored_layers_digest(mesh):
    """Checksum (hex string) of what the bake stored: BoxOffset and both quaternion UV maps as
    they are now, or None when one of them is missing."""
    import zlib

    attr = mesh.color_attributes.get(OFFSET_ATTRIBUTE)
    if attr is None or QUAT_XY_UV not in mesh.uv_layers or QUAT_ZW_UV not in mesh.uv_layers:
        return None
    count = len(mesh.vertices) if attr.domain == "POINT" else len(mesh.loops)
    buf = np.empty(count * 4, np.float32)
    if attr.data_type == "BYTE_COLOR":
        attr.data.foreach_get("color_srgb", buf)
        data = np.rint(buf * 255.0).astype(np.uint8)
    else:
        attr.data.foreach_get("color", buf)
        data = buf
    crc = zlib.crc32(memoryview(data).cast("B"))
    crc = zlib.crc32(f"{attr.data_type}/{attr.domain}/{count}".encode(), crc)
    for name in (QUAT_XY_UV, QUAT_ZW_UV):
        crc = zlib.crc32(memoryview(_read_uv(mesh, name, len(mesh.loops))).cast("B"), crc)
    return f"{crc:08x}"


def _colour_matches(mesh, name, data_type, domain) -> bool:
    attr = mesh.color_attributes.get(name)
    return attr is not None and attr.data_type == data_type and attr.domain == domain


def _read_offsets(mesh, settings, corner_verts, vertex_count) -> np.ndarray:
    """The stored BoxOffset per vertex in the core's layout (float32 or uint8 RGBA)."""
    attr = mesh.color_attributes[OFFSET_ATTRIBUTE]
    count = vertex_count if attr.domain == "POINT" else len(corner_verts)
    buf = np.empty(count * 4, np.float32)
    attr.data.foreach_get("color" if settings.encoding == "FLOAT_COLOR" else "color_srgb", buf)
    buf = buf.reshape(-1, 4)
    if attr.domain == "CORNER":
        per_vertex = np.empty((vertex_count, 4), np.float32)
        per_vertex[:] = NEUTRAL_FLOAT
        per_vertex[corner_verts] = buf
        buf = per_vertex
    if settings.encoding == "BYTE_COLOR":
        return np.rint(buf * 255.0).astype(np.uint8)
    return buf


@dataclass
class BakeSettings:
    angle_epsilon: float = 0.1
    origin: str = "BOUNDS"
    encoding: str = "FLOAT_COLOR"
    domain: str = "POINT"
    axis_turn: int = 0
    sort_axes_by_extent: bool = False
    use_cache: bool = True
    incremental: bool = True
    threads: int = 0


@dataclass
class PreparedBake:
    """A bake computed for one mesh and not yet written. ``write()`` stores it."""

    mesh: object
    settings: BakeSettings
    corner_verts: np.ndarray
    result: core.BakeResult
    keep_previous: bool
    report: dict = field(default_factory=dict)

    def write(self) -> dict:
        """Store the bake; call it once. The colour goes first so its buffer (the largest result
        array) is released before the UV maps are made, one corner buffer serves both UV maps, and
        the corner array is released once expanded: peak memory stays close to the size of the
        layers written. The result's per-submesh arrays stay for the caller."""
        mesh, s, r = self.mesh, self.settings, self.result
        if r.baked == 0:  # nothing changed: the stored data is already this bake's
            return self.report
        corner_count = len(self.corner_verts)
        previous_uv = {name: _read_uv(mesh, name, corner_count)
                       for name in (QUAT_XY_UV, QUAT_ZW_UV) if self.keep_previous and name in mesh.uv_layers}

        if not _colour_matches(mesh, OFFSET_ATTRIBUTE, s.encoding, s.domain):
            old = mesh.attributes.get(OFFSET_ATTRIBUTE)
            if old is not None:
                mesh.attributes.remove(old)
            mesh.color_attributes.new(OFFSET_ATTRIBUTE, s.encoding, s.domain)
        offsets = r.offsets
        if r.baked < r.submesh_count:  # the rows of submeshes not baked keep their stored colour
            if self.keep_previous:
                offsets = _read_offsets(mesh, s, self.corner_verts, len(r.submesh_of_vertex))
            else:  # a first bake of part of the mesh: the rest decodes to f = 0
                neutral = NEUTRAL_FLOAT if s.encoding == "FLOAT_COLOR" else NEUTRAL_BYTE
                offsets = np.empty_like(r.offsets)
                offsets[:] = neutral
            baked_vertex = r.written.view(bool)[r.submesh_of_vertex]
            offsets[baked_vertex] = r.offsets[baked_vertex]
            del baked_vertex
        if s.domain == "CORNER":
            offsets = offsets[self.corner_verts]
        if s.encoding == "FLOAT_COLOR":
            mesh.color_attributes[OFFSET_ATTRIBUTE].data.foreach_set("color", offsets.reshape(-1))
        else:
            # Raw bytes: color_srgb stores byte/255 untouched (color would apply the sRGB curve).
            raw = offsets.reshape(-1).astype(np.float32) / np.float32(255.0)
            mesh.color_attributes[OFFSET_ATTRIBUTE].data.foreach_set("color_srgb", raw)
            del raw
        del offsets
        r.offsets = None  # stored now; released so the UV maps do not add to the peak

        # UV maps in channel order, created without copying the active map's values.
        if len(mesh.uv_layers) == 0:
            mesh.uv_layers.new(name="UVMap")
        everything = r.baked == r.submesh_count
        buffer = None
        for half, name in enumerate((QUAT_XY_UV, QUAT_ZW_UV)):
            uv = previous_uv.pop(name, None)
            if uv is None:
                buffer = uv = np.empty((corner_count, 2), np.float32) if buffer is None else buffer
                if not everything:  # the identity quaternion where nothing is baked
                    uv[:, 0] = 0.0
                    uv[:, 1] = float(half)
            core.corner_quaternion_uv(uv, half, self.corner_verts, r, write_all=everything)
            if half == 1:  # expanded for the last time: gone before the last layer is made
                self.corner_verts = None
            if name not in mesh.uv_layers:
                mesh.uv_layers.new(name=name, do_init=False)
            _write_uv(mesh, name, uv)
            del uv
        del buffer

        if mesh.attributes.get(FINGERPRINT_ATTRIBUTE) is None:
            mesh.attributes.new(FINGERPRINT_ATTRIBUTE, "INT", "POINT")
        mesh.attributes[FINGERPRINT_ATTRIBUTE].data.foreach_set("value", r.fingerprints.view(np.int32))
        mesh.update()
        # What is stored now, so a later Skip Unchanged can tell whether it still is.
        mesh[LAYERS_DIGEST] = stored_layers_digest(mesh)
        names = [uv_map.name for uv_map in mesh.uv_layers]
        self.report["uv_channels"] = (names.index(QUAT_XY_UV), names.index(QUAT_ZW_UV))
        return self.report


def prepare_bake(mesh, settings: BakeSettings, selected_only: bool = False) -> PreparedBake:
    """Read the mesh and compute its bake without writing anything. Raises BakeInputError with a
    user-facing reason when the mesh cannot be baked."""
    if mesh.library is not None:
        raise BakeInputError(f"mesh '{mesh.name}' is linked from a library and cannot be changed")
    if len(mesh.vertices) == 0:
        raise BakeInputError(f"mesh '{mesh.name}' is empty")
    if len(mesh.polygons) == 0:
        raise BakeInputError(f"mesh '{mesh.name}' has no faces (loose vertices or edges only)")
    other = mesh.attributes.get(OFFSET_ATTRIBUTE)
    if other is not None and mesh.color_attributes.get(OFFSET_ATTRIBUTE) is None:
        raise BakeInputError(f"mesh '{mesh.name}' has an attribute '{OFFSET_ATTRIBUTE}' that is not a colour "
                             f"({other.data_type} on {other.domain}): rename or remove it, the bake would replace it")
    existing_uv = [uv.name for uv in mesh.uv_layers]
    needed = max(len(existing_uv), 1) + sum(n not in existing_uv for n in (QUAT_XY_UV, QUAT_ZW_UV))
    if needed > MAX_UV_MAPS:
        raise BakeInputError(f"mesh '{mesh.name}' has {len(existing_uv)} UV maps; the bake needs two "
                             f"free slots of {MAX_UV_MAPS} for {QUAT_XY_UV} and {QUAT_ZW_UV}")
    positions = read_positions(mesh)
    edges, face_starts, face_sizes, corner_verts = read_topology(mesh)
    mask = None
    if selected_only:
        mask = read_vertex_selection(mesh)
        if not mask.any():
            raise BakeInputError(f"mesh '{mesh.name}' has no selected vertex")

    layers_present = (_colour_matches(mesh, OFFSET_ATTRIBUTE, settings.encoding, settings.domain)
                      and QUAT_XY_UV in mesh.uv_layers and QUAT_ZW_UV in mesh.uv_layers)
    previous = None
    fp_attr = mesh.attributes.get(FINGERPRINT_ATTRIBUTE)
    if settings.incremental and layers_present and fp_attr is not None and fp_attr.domain == "POINT":
        # The fingerprints cover geometry and options; the checksum covers what is stored (an
        # edit to BoxOffset or the quaternion maps, e.g. a UV unwrap on the active map, would
        # otherwise survive as "unchanged"). A changed checksum re-bakes the whole mesh.
        if mesh.get(LAYERS_DIGEST) == stored_layers_digest(mesh):
            previous = np.empty(len(mesh.vertices), np.int32)
            fp_attr.data.foreach_get("value", previous)
            previous = previous.view(np.uint32)
    keep_previous = layers_present and (previous is not None or mask is not None)
    try:
        result = core.bake(positions, edges, face_starts, face_sizes, corner_verts, mask=mask,
                           previous_fingerprints=previous,
                           angle_epsilon=settings.angle_epsilon, origin=settings.origin,
                           sort_axes_by_extent=settings.sort_axes_by_extent,
                           axis_turn=settings.axis_turn, encoding=settings.encoding,
                           use_cache=settings.use_cache, threads=settings.threads)
    except ValueError as error:
        raise BakeInputError(f"mesh '{mesh.name}': {error}") from None
    report = {
        "mesh": mesh.name, "submeshes": result.submesh_count, "baked": result.baked,
        "cache_hits": result.cache_hits, "unchanged": result.unchanged,
        "not_selected": result.not_selected, "degenerate": result.degenerate,
        "max_error": result.max_error, "max_relative_error": result.max_relative_error,
    }
    return PreparedBake(mesh, settings, corner_verts, result, keep_previous, report)

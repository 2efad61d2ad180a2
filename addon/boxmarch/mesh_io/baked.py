"""The baked layers of a mesh: computing a bake (prepare_bake), storing it (PreparedBake.write) and
reading what is stored (read_baked_layers: the one reader, used by the re-bake, the export and the
preview)."""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from .. import core
from ..formats import layouts
from .arrays import new_zero_uv, read_positions, read_topology, read_uv, read_vertex_selection, write_uv
from .box_layers import BoxLayerError, BoxLayers, compute_box_layers, object_parameters, write_box_layers

OFFSET_ATTRIBUTE = "BoxOffset"
QUAT_XY_UV = layouts.QUAT_XY_UV  # the frame's quaternion, as CLASSIC and UV_FRAME carry it in UV1, UV2
QUAT_ZW_UV = layouts.QUAT_ZW_UV
BAKED_UV_MAPS = (QUAT_XY_UV, QUAT_ZW_UV)  # the UV maps the bake writes: never a tool's target
FINGERPRINT_ATTRIBUTE = ".boxmarch_fingerprint"
LAYERS_DIGEST = "_boxmarch_layers"  # mesh custom property: checksum of the stored layers
MAX_UV_MAPS = 8

# Colour written where nothing was baked yet: decodes to f = 0 (float) and the identity frame.
NEUTRAL_FLOAT = np.array([0.5, 0.5, 0.5, 1.0], np.float32)
NEUTRAL_BYTE = np.array([128, 128, 128, 255], np.uint8)


class BakeInputError(ValueError):
    """The mesh cannot be baked as it is; the message says why. Nothing was written."""


class NotBakedError(ValueError):
    """The mesh lacks a baked layer; the message names the mesh and the missing layers."""


def modifier_warnings(objects, action: str = "bake") -> list:
    """One line per object whose enabled modifiers or shape keys change what the viewport shows:
    the bake and the export read the mesh data (the base mesh), so the shown mesh would not
    decode."""
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
        keys = shape_key_warning(ob, action)
        if keys:
            warnings.append(keys)
    return warnings


def shape_key_warning(ob, action: str) -> str | None:
    """The warning for an object whose shape keys move the shape the viewport shows (the bake,
    the export and the preview read the mesh data without them), or None."""
    keys = shown_shape_keys(ob)
    if not keys:
        return None
    return (f"object '{ob.name}' shows shape key{'s' if len(keys) > 1 else ''} {', '.join(repr(k) for k in keys)}: "
            f"the {action} uses the mesh without them, so the shape shown does not decode (set their values to 0, "
            "or apply them: Object > Convert > Mesh, then bake)")


def shown_shape_keys(ob) -> list:
    """Names of the shape keys that move the shape the viewport shows away from the mesh data:
    the pinned key (Shape Key Lock) when it is not the reference, else every unmuted key other
    than the reference with a nonzero value."""
    data = getattr(ob, "data", None)
    shape_keys = getattr(data, "shape_keys", None)
    if shape_keys is None or len(shape_keys.key_blocks) < 2:
        return []
    reference = shape_keys.reference_key
    if ob.show_only_shape_key:
        key = ob.active_shape_key
        return [key.name] if key is not None and key != reference else []
    if not shape_keys.use_relative:  # absolute keys: the evaluation time picks the shape
        return [k.name for k in shape_keys.key_blocks if k != reference] if shape_keys.eval_time > 0 else []
    return [k.name for k in shape_keys.key_blocks if k != reference and not k.mute and k.value != 0.0]


def _read_offset_colour(attr, count) -> np.ndarray:
    """The stored BoxOffset colour, (count, 4) in the core's layout: float32 for FLOAT_COLOR, the
    raw bytes (uint8) for BYTE_COLOR (color_srgb holds byte/255 untouched; color would apply the
    sRGB curve)."""
    buf = np.empty(count * 4, np.float32)
    if attr.data_type == "BYTE_COLOR":
        attr.data.foreach_get("color_srgb", buf)
        return np.rint(buf * 255.0).astype(np.uint8).reshape(-1, 4)
    attr.data.foreach_get("color", buf)
    return buf.reshape(-1, 4)


def stored_layers_digest(mesh):
    """Checksum (hex string) of what the bake stored: BoxOffset and both quaternion UV maps as
    they are now, or None when one of them is missing."""
    attr = mesh.color_attributes.get(OFFSET_ATTRIBUTE)
    if attr is None or QUAT_XY_UV not in mesh.uv_layers or QUAT_ZW_UV not in mesh.uv_layers:
        return None
    count = len(mesh.vertices) if attr.domain == "POINT" else len(mesh.loops)
    crc = zlib.crc32(memoryview(np.ascontiguousarray(_read_offset_colour(attr, count))).cast("B"))
    crc = zlib.crc32(f"{attr.data_type}/{attr.domain}/{count}".encode(), crc)
    for name in (QUAT_XY_UV, QUAT_ZW_UV):
        crc = zlib.crc32(memoryview(read_uv(mesh, name)).cast("B"), crc)
    return f"{crc:08x}"


@dataclass
class BakedLayers:
    """What a bake stored in a mesh, as arrays."""

    encoding: str             # FLOAT_COLOR or BYTE_COLOR
    offsets: np.ndarray       # (vertices, 4) BoxOffset per vertex in the core's layout (float32 or uint8 raw bytes)
    quat_xy: np.ndarray       # float32 (corners, 2)
    quat_zw: np.ndarray       # float32 (corners, 2)
    corner_verts: np.ndarray  # int32 (corners,)

    def shader_offsets(self) -> np.ndarray:
        """float32 (vertices, 4) BoxOffset as a shader reads it (raw bytes / 255 for 8-bit colour)."""
        if self.offsets.dtype == np.uint8:
            return self.offsets.astype(np.float32) / np.float32(255.0)
        return self.offsets

    def vertex_quaternions(self) -> np.ndarray:
        """float32 (vertices, 4) (x, y, z, w): the quaternion of each vertex's last corner."""
        return core.vertex_values_from_corners(np.concatenate([self.quat_xy, self.quat_zw], axis=1),
                                               self.corner_verts, len(self.offsets))


def _offsets_per_vertex(attr, corner_verts, vertex_count) -> np.ndarray:
    """The stored BoxOffset per vertex in the core's layout; from the corner domain each vertex
    takes its last corner's colour (the bake writes one colour to every corner of a vertex), a
    vertex without corners the neutral colour."""
    if attr.domain == "POINT":
        return _read_offset_colour(attr, vertex_count)
    corners = _read_offset_colour(attr, len(corner_verts))
    per_vertex = np.empty((vertex_count, 4), corners.dtype)
    per_vertex[:] = NEUTRAL_BYTE if corners.dtype == np.uint8 else NEUTRAL_FLOAT
    per_vertex[corner_verts] = corners
    return per_vertex


def stray_bake_layers(mesh) -> list:
    """Descriptions of the layers named as the bake's (BoxOffset colour, BoxQuatXY, BoxQuatZW) on
    a mesh that holds no bake: not all three, and no checksum of a bake. They are the artist's
    (a UV map named BoxQuatXY), which a bake would overwrite."""
    present = ([f"a colour attribute '{OFFSET_ATTRIBUTE}'"] if mesh.color_attributes.get(OFFSET_ATTRIBUTE) else []) + [
        f"a UV map '{name}'" for name in BAKED_UV_MAPS if name in mesh.uv_layers]
    if len(present) == 1 + len(BAKED_UV_MAPS) or mesh.get(LAYERS_DIGEST) is not None:
        return []
    return present


def read_baked_layers(mesh, corner_verts=None) -> BakedLayers:
    """The baked layers of ``mesh`` (``corner_verts`` as read_topology gives it, read when None).
    Raises NotBakedError naming the missing layers."""
    attr = mesh.color_attributes.get(OFFSET_ATTRIBUTE)
    missing = ([OFFSET_ATTRIBUTE] if attr is None else []) + [
        name for name in (QUAT_XY_UV, QUAT_ZW_UV) if name not in mesh.uv_layers]
    if missing:
        raise NotBakedError(f"mesh '{mesh.name}' is not baked (missing {', '.join(missing)})")
    if corner_verts is None:
        corner_verts = read_topology(mesh)[3]
    return BakedLayers(attr.data_type, _offsets_per_vertex(attr, corner_verts, len(mesh.vertices)),
                       read_uv(mesh, QUAT_XY_UV), read_uv(mesh, QUAT_ZW_UV), corner_verts)


def _colour_matches(mesh, name, data_type, domain) -> bool:
    attr = mesh.color_attributes.get(name)
    return attr is not None and attr.data_type == data_type and attr.domain == domain


@dataclass
class BakeSettings:
    angle_epsilon: float = core.ANGLE_EPSILON_DEFAULT
    origin: str = core.ORIGIN_MODES[0]
    encoding: str = core.ENCODINGS[0]
    domain: str = "POINT"
    axis_turn: int = 0
    sort_axes_by_extent: bool = False
    use_cache: bool = True
    incremental: bool = True
    threads: int = 0
    hierarchy: str = core.HIERARCHY_RULES[0]
    random_seed: int = 0


@dataclass
class PreparedBake:
    """A bake computed for one mesh and not yet written. ``write()`` stores it."""

    mesh: object
    settings: BakeSettings
    corner_verts: np.ndarray
    result: core.BakeResult
    keep_previous: bool
    report: dict = field(default_factory=dict)
    box_layers: BoxLayers | None = None

    def write(self) -> dict:
        """Store the bake; call it once. The colour goes first so its buffer (the largest result
        array) is released before the UV maps are made, one corner buffer serves both UV maps, and
        the corner array is released once expanded: peak memory stays close to the size of the
        layers written. The result's per-submesh arrays stay for the caller."""
        mesh, s, r = self.mesh, self.settings, self.result
        if self.box_layers is not None:  # painted values may change without the geometry
            write_box_layers(mesh, r.submesh_of_vertex, self.box_layers)
        if r.baked == 0:  # nothing changed: the stored data is already this bake's
            mesh.update()
            return self.report
        corner_count = len(self.corner_verts)
        previous_uv = {name: read_uv(mesh, name)
                       for name in (QUAT_XY_UV, QUAT_ZW_UV) if self.keep_previous and name in mesh.uv_layers}

        if not _colour_matches(mesh, OFFSET_ATTRIBUTE, s.encoding, s.domain):
            old = mesh.attributes.get(OFFSET_ATTRIBUTE)
            if old is not None:
                mesh.attributes.remove(old)
            mesh.color_attributes.new(OFFSET_ATTRIBUTE, s.encoding, s.domain)
        offsets = r.offsets
        if r.baked < r.submesh_count:  # the rows of submeshes not baked keep their stored colour
            if self.keep_previous:
                offsets = _offsets_per_vertex(mesh.color_attributes[OFFSET_ATTRIBUTE], self.corner_verts,
                                              len(r.submesh_of_vertex))
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
        if len(mesh.uv_layers) == 0:  # the artist's channel, so the box maps are UV1 and UV2
            new_zero_uv(mesh, "UVMap")
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
            write_uv(mesh, name, uv)
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
    seed = settings.random_seed
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed <= core.RANDOM_SEED_MAX:
        raise BakeInputError(f"random seed must be a whole number in 0..{core.RANDOM_SEED_MAX}, got {seed!r}")
    if len(mesh.vertices) == 0:
        raise BakeInputError(f"mesh '{mesh.name}' is empty")
    if len(mesh.polygons) == 0:
        raise BakeInputError(f"mesh '{mesh.name}' has no faces (loose vertices or edges only)")
    other = mesh.attributes.get(OFFSET_ATTRIBUTE)
    if other is not None and mesh.color_attributes.get(OFFSET_ATTRIBUTE) is None:
        raise BakeInputError(f"mesh '{mesh.name}' has an attribute '{OFFSET_ATTRIBUTE}' that is not a colour "
                             f"({other.data_type} on {other.domain}): rename or remove it, the bake would replace it")
    stray = stray_bake_layers(mesh)
    if stray:
        raise BakeInputError(f"mesh '{mesh.name}' holds no bake, yet has {' and '.join(stray)} (the names of the "
                             "layers the bake writes): the bake would overwrite them; rename them (e.g. an own UV "
                             "map 'BoxQuatXY' to 'UVMap') or remove them")
    existing_uv = [uv.name for uv in mesh.uv_layers]
    needed = max(len(existing_uv), 1) + sum(n not in existing_uv for n in (QUAT_XY_UV, QUAT_ZW_UV))
    if needed > MAX_UV_MAPS:
        raise BakeInputError(f"mesh '{mesh.name}' has {len(existing_uv)} UV maps; the bake needs two "
                             f"free slots of {MAX_UV_MAPS} for {QUAT_XY_UV} and {QUAT_ZW_UV}")
    positions = read_positions(mesh)
    edges, face_starts, face_sizes, corner_verts = read_topology(mesh)
    mask = None
    if selected_only:
        mask = read_vertex_selection(mesh).view(np.uint8)
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
                           use_cache=settings.use_cache, threads=settings.threads,
                           arrays_owned=True)  # read from Blender for this bake: no other code holds them
    except ValueError as error:
        raise BakeInputError(f"mesh '{mesh.name}': {error}") from None
    try:
        box_layers, box_report = compute_box_layers(
            mesh, result, face_starts, corner_verts,
            _boxes_for_hierarchy(mesh, result, positions, corner_verts, keep_previous, settings.hierarchy),
            settings.hierarchy, settings.random_seed, object_parameters(mesh))
    except BoxLayerError as error:
        raise BakeInputError(str(error)) from None
    not_box, off_box = core.not_boxes(positions, result.submesh_of_vertex, result.quaternions)
    not_box &= result.written.view(bool)  # the frames of the submeshes baked now
    example = int(np.argmax(not_box))
    report = {
        "mesh": mesh.name, "submeshes": result.submesh_count, "baked": result.baked,
        "not_boxes": int(not_box.sum()),
        "not_box_example": {"submesh": example, "vertices": int(np.count_nonzero(result.submesh_of_vertex == example)),
                            "off_box": float(off_box[example])} if not_box.any() else None,
        "cache_hits": result.cache_hits, "unchanged": result.unchanged,
        "not_selected": result.not_selected, "degenerate": result.degenerate,
        "max_error": result.max_error, "max_relative_error": result.max_relative_error,
        "boxes": box_report,
    }
    return PreparedBake(mesh, settings, corner_verts, result, keep_previous, report, box_layers)


def _boxes_for_hierarchy(mesh, result, positions, corner_verts, keep_previous, rule):
    """(origins, quaternions, half-extents) of every box after this bake, for the geometric
    hierarchy rules: this bake's where it baked, the stored layers' elsewhere (zeros where
    nothing is stored yet). The ATTRIBUTE rule reads none: this bake's arrays stand in."""
    boxes = (result.origins, result.quaternions, result.half_extents)
    if rule == "ATTRIBUTE" or result.baked == result.submesh_count or not keep_previous:
        return boxes
    stored = read_baked_layers(mesh, corner_verts)
    merged = core.boxes_from_bake(positions, stored.offsets, stored.vertex_quaternions(), result.submesh_of_vertex)
    written = result.written.view(bool)
    for old, new in zip(merged, boxes):
        old[written] = new[written]
    return merged

"""Per-box parameters and hierarchy in Blender mesh data: reading what the artist painted
(``boxmarch_shape``, ``boxmarch_material``, ``boxmarch_user``, ``boxmarch_parent``, or one colour
``boxmarch_params``), reducing it to one value per box (core), and the stored layers the bake
writes (``.boxmarch_shape_material``, ``.boxmarch_random_user``, ``.boxmarch_parent``,
``.boxmarch_depth``) that the export and the preview read. docs/FORMAT.md states the names and the rules."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import core
from .weights import SkinError, read_skin

# Artist-facing attributes: one scalar per element (FLOAT, INT, INT8 or BOOLEAN) on the point,
# face or corner domain; or one colour whose R, G and A give shape, material and user (its B is
# ignored: the random slot is the bake's). A scalar attribute wins over the colour's channel.
PARAM_ATTRIBUTES = {"shape": "boxmarch_shape", "material": "boxmarch_material", "user": "boxmarch_user"}
PARAMS_COLOUR_ATTRIBUTE = "boxmarch_params"
PARENT_ATTRIBUTE = "boxmarch_parent"
# What the bake stores, per vertex (hidden: the names start with a dot). Pairs of floats, not
# one colour: a colour attribute could become the mesh's active or render colour.
PARAMS_LAYERS = (".boxmarch_shape_material", ".boxmarch_random_user")  # FLOAT2 POINT
PARENT_LAYER = ".boxmarch_parent"   # INT POINT: the parent box's index, -1 for a root
DEPTH_LAYER = ".boxmarch_depth"     # INT POINT: 0 at a root
# INT POINT: the box's own number at the bake. Parents name boxes by number; deleting a box, or
# joining baked meshes, renumbers the boxes after the bake, and this layer tells which number each
# box had (read_box_layers maps the parents onto today's numbers, or finds them stale).
BOX_NUMBER_LAYER = ".boxmarch_box"
# Only the random values are always stored: see write_box_layers.
_SCALAR_TYPES = {"FLOAT": ("value", np.float32), "INT": ("value", np.int32), "INT8": ("value", np.int32),
                 "BOOLEAN": ("value", bool)}
_COLOUR_CHANNELS = {"shape": 0, "material": 1, "user": 3}
FLOAT32_MAX = float(np.finfo(np.float32).max)  # a larger parameter would be written as infinity


class BoxLayerError(ValueError):
    """An artist attribute cannot give per-box values; the message names it and says why."""


@dataclass
class BoxLayers:
    """Per-box values of one mesh: ``params`` float32 (S, 4) in PARAM_NAMES order, ``parent``
    and ``depth`` int32 (S,); ``stale_parents``: how many boxes' stored parents no longer name a
    box since the bake (read_box_layers made them roots)."""

    params: np.ndarray
    parent: np.ndarray
    depth: np.ndarray
    stale_parents: int = 0


def _element_submesh(domain, submesh_of_vertex, face_starts, corner_verts):
    if domain == "POINT":
        return submesh_of_vertex
    if domain == "CORNER":
        return submesh_of_vertex[corner_verts]
    if domain == "FACE":
        return submesh_of_vertex[corner_verts[face_starts]]
    return None


def _read_element_values(mesh, name, domain_size):
    """(float32 (E, k), domain) of attribute ``name``, or None when the mesh has none."""
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    if attr.domain not in ("POINT", "FACE", "CORNER"):
        raise BoxLayerError(f"mesh '{mesh.name}': attribute '{name}' is on the {attr.domain} domain; "
                            "use POINT, FACE or CORNER")
    count = domain_size[attr.domain]
    if attr.data_type in ("FLOAT_COLOR", "BYTE_COLOR"):
        buf = np.empty(count * 4, np.float32)
        # color_srgb holds a byte colour's byte/255 untouched (color would apply the sRGB curve).
        attr.data.foreach_get("color" if attr.data_type == "FLOAT_COLOR" else "color_srgb", buf)
        return buf.reshape(-1, 4), attr.domain
    if attr.data_type not in _SCALAR_TYPES:
        raise BoxLayerError(f"mesh '{mesh.name}': attribute '{name}' is {attr.data_type}; "
                            "use FLOAT, INT, BOOLEAN or a colour")
    prop, dtype = _SCALAR_TYPES[attr.data_type]
    buf = np.empty(count, dtype)
    attr.data.foreach_get(prop, buf)
    if dtype is np.int32:  # kept whole: float32 would round 16777217 to 16777216 (_reduce)
        return buf[:, None], attr.domain
    return buf.astype(np.float32)[:, None], attr.domain


def _reduce(mesh, name, submesh_of_vertex, count, face_starts, corner_verts, disagreements):
    sizes = {"POINT": len(mesh.vertices), "FACE": len(mesh.polygons), "CORNER": len(mesh.loops)}
    read = _read_element_values(mesh, name, sizes)
    if read is None:
        return None
    values, domain = read
    whole = values.dtype == np.int32
    if whole:  # each int32 as its two 16-bit halves, both exact in float32: the same majority, every bit kept
        values = np.concatenate([values >> 16, values & 0xFFFF], 1).astype(np.float32)
    try:
        per_box, disagrees, n = core.reduce_per_submesh(
            values, _element_submesh(domain, submesh_of_vertex, face_starts, corner_verts), count)
    except ValueError as error:
        raise BoxLayerError(f"mesh '{mesh.name}': attribute '{name}': {error}") from None
    if whole:  # float64: the parent rule reads the whole number; parameters become float32 where stored
        per_box = per_box[:, :1].astype(np.float64) * 65536 + per_box[:, 1:]
    if n:
        disagreements[name] = {"submeshes": n, "first": [int(s) for s in np.flatnonzero(disagrees)[:8]]}
    return per_box


def object_parameters(mesh) -> dict:
    """{parameter key: value} of the custom properties named as PARAM_ATTRIBUTES on the objects
    using ``mesh`` (linked duplicates share the mesh and so its bake: every one that gives a
    value must give the same, and one that gives none with one that does is refused too).
    Raises BoxLayerError naming the objects."""
    users = _mesh_users(mesh)
    values = {}
    for key, name in PARAM_ATTRIBUTES.items():
        given = {ob.name: ob.get(name) for ob in users}
        for ob_name, value in given.items():
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                      or not abs(value) <= FLOAT32_MAX):
                raise BoxLayerError(f"object '{ob_name}': property '{name}' is {value!r}; give a finite number "
                                    f"within float32's range (±{FLOAT32_MAX:.7g}), the box table's")
        if all(v is None for v in given.values()):
            continue
        if len(set(given.values())) > 1:
            listed = ", ".join(f"'{k}' {'none' if v is None else v}" for k, v in sorted(given.items()))
            raise BoxLayerError(f"mesh '{mesh.name}' is shared by objects whose property '{name}' differs ({listed}): "
                                "the bake is per mesh; give them the same value, or make the mesh single-user "
                                "(Object > Relations > Make Single User > Object & Data)")
        values[key] = float(next(iter(given.values())))
    return values


def _mesh_users(mesh) -> list:
    """The objects using ``mesh`` (linked duplicates share it, and so its bake)."""
    import bpy

    return [ob for ob in bpy.data.objects if ob.type == "MESH" and ob.data == mesh and ob.users]


def bone_parents(mesh, submesh_of_vertex, count, origins) -> np.ndarray:
    """int32 (S,): the BONES rule's parents of ``mesh``'s boxes (core.parents_by_bone): each
    box's bone is the deform bone with the most weight over its vertices, of the Armature
    modifier of the objects using the mesh; a bone's parent is its nearest ancestor bone that
    weights some vertex. Raises BoxLayerError without such a modifier, or where the users are
    skinned differently."""
    try:
        skins = {ob.name: read_skin(ob) for ob in _mesh_users(mesh)}
    except SkinError as error:
        raise BoxLayerError(f"mesh '{mesh.name}': {error}") from None
    rigs = {(skin.armature.name, tuple(skin.bones)) for skin in skins.values() if skin is not None}
    if not rigs:
        raise BoxLayerError(f"mesh '{mesh.name}': the BONES rule needs an object using it with an Armature modifier "
                            "whose deform bones weight its vertices (vertex groups named as the bones)")
    if len(rigs) > 1 or None in skins.values():
        raise BoxLayerError(f"mesh '{mesh.name}' is shared by objects skinned by different armatures or none "
                            f"({', '.join(sorted(skins))}): the BONES rule needs one")
    skin = next(iter(skins.values()))
    column = {name: k for k, name in enumerate(skin.bones)}
    bone_parent = []
    for name in skin.bones:
        up = skin.armature.data.bones[name].parent
        while up is not None and up.name not in column:
            up = up.parent
        bone_parent.append(-1 if up is None else column[up.name])
    box_bone = core.dominant_per_submesh(skin.weights, submesh_of_vertex, count)
    return core.parents_by_bone(box_bone, bone_parent, origins)


def compute_box_layers(mesh, result, face_starts, corner_verts, boxes, rule="ATTRIBUTE", seed=0, object_values=None):
    """(BoxLayers, report dict) for a bake ``result`` of ``mesh``. ``boxes`` = (origins,
    quaternions, half_extents) per submesh, used by the CONTAINMENT, CHAIN and BONES rules.
    ``object_values`` ({parameter key: value}, object_parameters) gives every box a value no
    attribute paints. Raises BoxLayerError on an attribute that cannot be read or parents that
    do not form a tree."""
    sv, count = result.submesh_of_vertex, result.submesh_count
    disagreements = {}
    object_values = object_values or {}
    params = np.zeros((count, 4), np.float32)
    colour = _reduce(mesh, PARAMS_COLOUR_ATTRIBUTE, sv, count, face_starts, corner_verts, disagreements)
    if colour is not None and colour.shape[1] != 4:
        raise BoxLayerError(f"mesh '{mesh.name}': attribute '{PARAMS_COLOUR_ATTRIBUTE}' must be a colour "
                            "(FLOAT_COLOR or BYTE_COLOR)")
    for key, name in PARAM_ATTRIBUTES.items():
        column = core.PARAM_NAMES.index(key)
        scalar = _reduce(mesh, name, sv, count, face_starts, corner_verts, disagreements)
        if scalar is not None:
            params[:, column] = scalar[:, 0]
        elif colour is not None:
            params[:, column] = colour[:, _COLOUR_CHANNELS[key]]
        elif key in object_values:
            params[:, column] = object_values[key]
    params[:, core.PARAM_NAMES.index("random")] = core.box_random(
        core.box_fingerprints(result.fingerprints, sv, count), seed)
    given = None
    if rule == "ATTRIBUTE":
        given = _reduce(mesh, PARENT_ATTRIBUTE, sv, count, face_starts, corner_verts, disagreements)
        given = None if given is None else given[:, 0]
    elif rule == "BONES":
        given = bone_parents(mesh, sv, count, boxes[0])
    try:
        if rule == "ATTRIBUTE" and given is None:  # nothing asked: every box a root, no pass over the boxes
            parent, depth, deepest = np.full(count, -1, np.int32), np.zeros(count, np.int32), 0
        else:
            parent, depth, deepest = core.box_hierarchy(*boxes, rule=rule, given_parent=given)
    except ValueError as error:
        raise BoxLayerError(f"mesh '{mesh.name}': box hierarchy: {error}") from None
    report = {"hierarchy": rule, "max_depth": deepest, "roots": int((parent < 0).sum()),
              "random_seed": int(seed), "disagreeing_attributes": disagreements,
              "object_properties": {PARAM_ATTRIBUTES[k]: v for k, v in object_values.items()}}
    return BoxLayers(params, parent, depth), report


# What a layer holds where nothing is painted and every box is a root: such a layer is not
# stored (read_box_layers reads its absence as these values), so a plain bake writes one layer
# per vertex (the random values) instead of four.
_LAYER_DEFAULTS = {PARAMS_LAYERS[0]: 0.0, PARENT_LAYER: -1, DEPTH_LAYER: 0}


def write_box_layers(mesh, submesh_of_vertex, layers: BoxLayers) -> None:
    """Store ``layers`` per vertex (every vertex holds its box's values); a layer whose every box
    holds its default (_LAYER_DEFAULTS) is removed instead, and so are the box numbers where no
    box has a parent (nothing names a box by its number)."""
    roots_only = bool(np.all(layers.parent == -1))
    for name, data_type, values, prop in ((PARAMS_LAYERS[0], "FLOAT2", layers.params[:, :2], "vector"),
                                          (PARAMS_LAYERS[1], "FLOAT2", layers.params[:, 2:], "vector"),
                                          (PARENT_LAYER, "INT", layers.parent, "value"),
                                          (DEPTH_LAYER, "INT", layers.depth, "value"),
                                          (BOX_NUMBER_LAYER, "INT", np.arange(len(layers.parent), dtype=np.int32),
                                           "value")):
        unneeded = (np.all(values == _LAYER_DEFAULTS[name]) if name in _LAYER_DEFAULTS
                    else name == BOX_NUMBER_LAYER and roots_only)
        attr = mesh.attributes.get(name)
        if attr is not None and (unneeded or attr.data_type != data_type or attr.domain != "POINT"):
            mesh.attributes.remove(attr)
            attr = None
        if unneeded:
            continue
        if attr is None:
            attr = mesh.attributes.new(name, data_type, "POINT")
        attr.data.foreach_set(prop, np.ascontiguousarray(values[submesh_of_vertex]).reshape(-1))


def read_box_layers(mesh, submesh_of_vertex, count):
    """The stored BoxLayers of ``mesh`` per box (each box takes its lowest vertex's values; a
    layer not stored holds its default), or None when the mesh was baked without them (no random
    values stored)."""
    attrs = {name: mesh.attributes.get(name) for name in (*PARAMS_LAYERS, PARENT_LAYER, DEPTH_LAYER)}
    attrs = {name: a for name, a in attrs.items() if a is not None and a.domain == "POINT"}
    if PARAMS_LAYERS[1] not in attrs:
        return None
    n = len(mesh.vertices)
    first = np.zeros(int(count), np.int64)
    first[submesh_of_vertex[::-1]] = np.arange(n)[::-1]

    def per_box(name, dtype, width, prop):
        if name not in attrs:
            return np.full((int(count), width), _LAYER_DEFAULTS[name], dtype)
        values = np.empty(n * width, dtype)
        attrs[name].data.foreach_get(prop, values)
        return values.reshape(n, width)[first]

    params = np.concatenate([per_box(name, np.float32, 2, "vector") for name in PARAMS_LAYERS], 1)
    number = mesh.attributes.get(BOX_NUMBER_LAYER)
    baked_number = None
    if number is not None and number.domain == "POINT" and number.data_type == "INT":
        baked_number = np.empty(n, np.int32)
        number.data.foreach_get("value", baked_number)
        baked_number = baked_number[first]
    parent, depth, stale = current_parents(per_box(PARENT_LAYER, np.int32, 1, "value")[:, 0],
                                           per_box(DEPTH_LAYER, np.int32, 1, "value")[:, 0], baked_number)
    return BoxLayers(params, parent, depth, stale)


def current_parents(parent, depth, baked_number=None):
    """(parent int32, depth int32, stale count) of boxes whose stored ``parent`` and ``depth``
    name boxes by the number each had at the bake, ``baked_number`` (S,) (None: a bake that did
    not store it; the numbers are taken as unchanged): each parent mapped onto the box that holds
    its number now. A parent is stale, and its box becomes a root, where no box or two boxes hold
    its number (a box deleted, baked meshes joined), where it would be the box itself, or where
    the stored depths disagree with it (its box's depth is not its parent's plus one); depths are
    then counted again. A parent out of range or a box its own parent is never returned."""
    parent = np.asarray(parent, np.int64)
    depth = np.asarray(depth, np.int64)
    count = len(parent)
    boxes = np.arange(count)
    resolved = parent
    if baked_number is not None and not np.array_equal(baked_number, boxes):
        order = np.argsort(baked_number, kind="stable")
        numbers = np.asarray(baked_number, np.int64)[order]
        held_once = np.ones(count, bool)
        held_once[1:] &= numbers[1:] != numbers[:-1]
        held_once[:-1] &= numbers[:-1] != numbers[1:]
        at = np.minimum(np.searchsorted(numbers, parent), count - 1)
        found = (numbers[at] == parent) & held_once[at]
        resolved = np.where(parent < 0, -1, np.where(found, order[at], -2))
    inside = (resolved >= 0) & (resolved < count)
    up_depth = depth[np.where(inside, resolved, 0)] if count else depth
    stale = ((resolved != -1) & ~inside) | (resolved == boxes) | (inside & (depth != up_depth + 1))
    if not stale.any() and resolved is parent:
        return parent.astype(np.int32), depth.astype(np.int32), 0
    resolved = np.where(stale, -1, resolved).astype(np.int32)
    # Depth falls by one along every parent kept, so the parents form a tree: count the depths again.
    _, depth, _ = core.box_hierarchy(np.zeros((count, 3)), np.tile(np.float32([0, 0, 0, 1]), (count, 1)),
                                     np.zeros((count, 3)), rule="ATTRIBUTE", given_parent=resolved)
    return resolved, depth.astype(np.int32), int(stale.sum())

"""The box data of a baked mesh as a file must hold it: read through mesh_io, put in the space the
file writes the positions in (docs/EXPORT.md, Object transforms) and in the target's frame
(formats/transforms.py), with the checks the export reports: stale boxes, sheared boxes, skin weight
spreads, the decode measured on the written file. export/scene.py runs the exporters with it."""
from __future__ import annotations

import numpy as np

from .. import core, mesh_io
from ..formats import layouts
from ..formats import glb, transforms


class ExportInputError(ValueError):
    """The selection cannot be exported as it is; the message says why. Nothing was written."""


def baked_layers(mesh) -> mesh_io.BakedLayers:
    """The stored layers of a baked mesh (mesh_io.read_baked_layers). Raises ExportInputError
    when it is not baked."""
    try:
        return mesh_io.read_baked_layers(mesh)
    except mesh_io.NotBakedError as error:
        raise ExportInputError(f"{error}: run Bake Box Frames first") from None


def box_data(mesh, preset, index_base: int = 0, space=None):
    """(layouts.BoxData in the target's frame, corner_verts, stats, origins) of a baked mesh: the
    stored offsets and quaternion, each vertex's box half-extents (largest |f| per local axis over
    its submesh) and box number (``index_base`` + submesh id). ``space`` (4 x 4, Blender axes;
    None: the object's own) maps object coordinates to those the file writes positions in: a
    skinned glTF holds world positions, so its frames, offsets and half-extents are given in
    world space (transforms.frames_in_space; CLASSIC colours only in the object's own).
    ``origins`` (vertices, 3): where each vertex's box origin lies in the file's space, target
    axes (what the file must decode to); stats["sheared_boxes"] counts the boxes ``space``
    shears, whose data is not meaningful (the caller refuses them)."""
    layers = baked_layers(mesh)
    offsets, corner_verts, q = layers.shader_offsets(), layers.corner_verts, layers.vertex_quaternions()
    positions = mesh_io.read_positions(mesh).astype(np.float64)
    edges, face_starts, face_sizes, _ = mesh_io.read_topology(mesh)
    submesh_of_vertex, count = core.find_submeshes(positions.astype(np.float32), edges, face_starts, face_sizes,
                                                   corner_verts)
    _, _, box_half = core.boxes_from_bake(positions, offsets, q, submesh_of_vertex)
    f = core.decode_offsets(offsets)
    blender_origin = positions + core.rotate_vector(f, q)
    stale = stale_boxes(blender_origin, box_half, submesh_of_vertex, count, layers.encoding)
    sheared = 0
    if space is not None:
        space = np.asarray(space, np.float64)
        q, f, box_half, sheared = transforms.frames_in_space(q, f, box_half, submesh_of_vertex, space[:3, :3])
        positions = positions @ space[:3, :3].T + space[:3, 3]
        blender_origin = blender_origin @ space[:3, :3].T + space[:3, 3]
    target_q = transforms.target_quaternions(q, preset)
    target_f = transforms.target_local(f, preset)
    target_half = np.asarray(box_half, np.float64) * preset.length_scale
    # Self-check: the decode in the target frame must land where the target frame puts Blender's.
    origins = transforms.target_positions(blender_origin, preset)
    first_vertex = np.zeros(count, np.int64)  # one vertex of each box: its box's origin and frame
    first_vertex[submesh_of_vertex[::-1]] = np.arange(len(positions))[::-1]
    data = layouts.BoxData(quaternions=target_q, offsets=target_f, half_extents=target_half[submesh_of_vertex],
                           index=index_base + submesh_of_vertex.astype(np.int64),
                           classic_rgba=transforms.target_offsets(offsets, preset) if space is None else None,
                           box_half_extents=target_half, index_base=index_base,
                           box_origins=origins[first_vertex], box_quaternions=target_q[first_vertex])
    box_layers = mesh_io.read_box_layers(mesh, submesh_of_vertex, count)
    if box_layers is not None and not np.isfinite(box_layers.params).all():
        bad = sorted({core.PARAM_NAMES[i] for i in np.flatnonzero(~np.isfinite(box_layers.params).all(axis=0))})
        raise ExportInputError(f"mesh '{mesh.name}': its stored box parameters ({', '.join(bad)}) are not finite, "
                               "which no file may hold: give the objects' properties and the painted attributes "
                               "finite values, bake again, then export")
    if box_layers is not None:  # box numbers run on across the file's meshes: so do the parents
        data.box_params, data.box_depth = box_layers.params, box_layers.depth
        data.box_parent = np.where(box_layers.parent >= 0, box_layers.parent + index_base, -1)
    target_origin = transforms.target_positions(positions, preset) + core.rotate_vector(target_f, target_q)
    error = float(np.abs(target_origin - origins).max() / offset_reach(target_f)) if len(f) else 0.0
    stats = {"mesh": mesh.name, "vertices": len(positions), "corners": len(corner_verts), "boxes": int(count),
             "colour": layers.encoding, "max_alpha": float(offsets[:, 3].max()) / preset.length_scale if len(positions) else 0.0,
             "space": "object" if space is None else "world", "transform_error": error, "stale_boxes": stale,
             "sheared_boxes": sheared, "box_parameters": box_parameter_stats(data, box_layers is not None),
             "stale_parents": box_layers.stale_parents if box_layers is not None else 0}
    return data, corner_verts, stats, origins


def box_parameter_stats(data: layouts.BoxData, stored: bool) -> dict:
    """The export report's figures of a mesh's box parameters and hierarchy."""
    params, parent, depth = data.box_values()
    return {"stored": stored, "roots": int((parent < 0).sum()), "max_depth": int(depth.max()) if len(depth) else 0,
            **{f"{name}_range": [float(params[:, i].min()), float(params[:, i].max())] if len(params) else [0.0, 0.0]
               for i, name in enumerate(core.PARAM_NAMES)}}


def offset_reach(target_f) -> float:
    """The largest |f| component: the scale the report's decode errors are measured against."""
    return max(float(np.abs(target_f).max()) if len(target_f) else 0.0, 1e-30)


# The worst decode error of a file, over the largest offset, that float32 rounding of positions
# and channels explains; anything above means the box data is in another space than the positions.
FILE_DECODE_TOLERANCE = 1e-4
FLOAT32_POSITION_ERROR = 2.0 ** -22  # two roundings of a float32 position, relative to its size


# A box is stale when its vertices' decoded origins disagree by more than this fraction of its
# largest half-extent: a bake decodes them to one point within float32 rounding, or within the
# 8-bit colour's quantisation bound (docs/FORMAT.md); an edit after the bake that moves some of
# them does not.
STALE_SPREAD = {"FLOAT_COLOR": 1e-3, "BYTE_COLOR": 0.05}


def stale_boxes(decoded_origins, box_half, submesh_of_vertex, count, encoding) -> int:
    """How many boxes changed shape since the bake: the stored offsets and frames of their
    vertices no longer decode to one origin (moving or turning a whole box keeps it decoding)."""
    if not count:
        return 0
    high = np.full((count, 3), -np.inf)
    low = np.full((count, 3), np.inf)
    np.maximum.at(high, submesh_of_vertex, decoded_origins)
    np.minimum.at(low, submesh_of_vertex, decoded_origins)
    reach = np.maximum(np.asarray(box_half, np.float64).max(axis=1), 1e-30)
    return int(((high - low).max(axis=1) > STALE_SPREAD[encoding] * reach).sum())


def box_weight_spread(weights, box, boxes) -> np.ndarray:
    """(boxes,) the largest difference, over a box's vertices, of their weights on one bone:
    0 where the box is carried rigidly (docs/ACCURACY.md measures what a spread costs)."""
    high = np.full((boxes, weights.shape[1]), -np.inf)
    low = np.full((boxes, weights.shape[1]), np.inf)
    np.maximum.at(high, box, weights)
    np.minimum.at(low, box, weights)
    spread = np.where(np.isfinite(high), high - low, 0.0)
    return spread.max(axis=1) if weights.shape[1] else np.zeros(boxes)


# Weight differences inside a box below this are float noise of the artist's weights, not a blend.
RIGID_WEIGHT_SPREAD = 1e-6


def written_space(ob, skin, preset):
    """The space (4 x 4, Blender axes) the preset's file holds ``ob``'s positions in, for
    box_data: None for the object's own (its glTF node or FBX model carries its transform), the
    world for a skinned glTF (Blender's glTF exporter writes a skinned mesh's vertices in world
    space, the joints' inverse bind matrices holding the armature's world transform, so the skin
    at rest is the identity; the export measures it in the file, file_decode_error)."""
    if skin is None or preset.extension != ".glb":
        return None
    return np.array(ob.matrix_world, np.float64)


def file_decode_error(gltf, binary, name, layout, channels, origins) -> tuple[float, float]:
    """(worst decode error, what float32 positions explain), both over the largest offset, of the
    .glb's mesh ``name``: its POSITION as the exporter wrote it, plus the layout's offset decoded
    from ``channels`` (what glb.replace_vertex_channels writes, per Blender vertex), against
    ``origins`` (box_data: where each Blender vertex's box origin lies in the space the file
    should hold). Small boxes far from the origin lose to float32 positions alone about 1e-7 of
    the distance; the second figure adds that to FILE_DECODE_TOLERANCE."""
    worst = reach = position_reach = 0.0
    primitives = [p for mesh in gltf.get("meshes", []) if mesh.get("name") == name
                  for p in glb.vertex_indices(gltf, binary, mesh)]
    for attrs, index in primitives:
        positions = glb.accessor_array(gltf, binary, attrs["POSITION"]).astype(np.float64)
        to_origin = layouts.to_origin(layout, {k: v[index] for k, v in channels.items()})
        if len(index):
            worst = max(worst, float(np.abs(positions + to_origin - origins[index]).max()))
            reach = max(reach, float(np.abs(to_origin).max()))
            position_reach = max(position_reach, float(np.abs(positions).max()))
    reach = max(reach, 1e-30)
    return worst / reach, FILE_DECODE_TOLERANCE + FLOAT32_POSITION_ERROR * position_reach / reach


def refuse_shared_world_meshes(objects, skins, preset) -> None:
    """Raises ExportInputError where objects written in world space (written_space) share a mesh
    but not a world transform: the file's copies of it would need different box data."""
    first = {}
    for ob in objects:
        space = written_space(ob, skins.get(ob.name), preset)
        other = first.setdefault(ob.data.name_full, (ob, space))
        if other[0] is not ob and (space is not None or other[1] is not None) and not (
                space is not None and other[1] is not None and np.allclose(space, other[1])):
            raise ExportInputError(
                f"objects '{other[0].name}' and '{ob.name}' share the mesh '{ob.data.name}' and a skinned glTF holds "
                "each in world space, where their boxes differ: make the mesh single-user "
                "(Object > Relations > Make Single User > Object & Data), bake, then export")


def morph_warnings(objects, preset) -> list:
    """One line per object whose shape keys the file carries (glTF morph targets, FBX blend
    shapes): the morphs move positions only, so a morph that moves a box's vertices unevenly
    leaves its baked data behind."""
    if preset.raw_blend:
        return []
    out = []
    for ob in objects:
        keys = getattr(ob.data, "shape_keys", None)
        if keys is not None and len(keys.key_blocks) > 1:
            names = ", ".join(repr(k.name) for k in keys.key_blocks if k != keys.reference_key)
            out.append(f"object '{ob.name}' has shape keys ({names}): the file carries them as "
                       f"{'morph targets' if preset.extension == '.glb' else 'blend shapes'}, which move vertices "
                       "but not the baked boxes: a morph that moves a box's vertices unevenly makes it decode off")
    return out


def written_warnings(stats, objects, preset, layout) -> list:
    """The export's warnings about what the written file gets wrong, from each mesh's ``stats``
    (box_data's, completed by the export): float offsets that 8-bit vertex colours would clip,
    skins that do not move boxes rigidly, object parents a per-mesh numbering cannot name, boxes
    that decode off Blender's in the file, boxes and parents changed since the bake."""
    warnings = []
    if preset.colour_8bit and layouts.LAYOUTS[layout].classic_colour:
        floats = [m for m in stats if m["colour"] == "FLOAT_COLOR"]
        if floats:
            warnings.append(
                f"{', '.join(m['mesh'] for m in floats)}: float offsets (alpha up to "
                f"{max(m['max_alpha'] for m in floats):.3g}); Unity usually stores vertex colours as "
                "8-bit Color32, which clips alpha above 1 and rounds the rest: bake with 8-bit colour "
                "for Unity (docs/EXPORT.md)")
    for m in stats:
        skin = m.get("skin")
        if skin and skin["non_rigid_boxes"]:
            warnings.append(f"{m['mesh']}: {skin['non_rigid_boxes']} of {m['boxes']} boxes have vertices with different "
                            f"bone weights (up to {skin['worst_weight_spread']:.2g} apart): posed, their decoded origins "
                            "leave the boxes (docs/ACCURACY.md); weight each box to its bones alike")
        if skin and skin["unweighted_vertices"]:
            warnings.append(f"{m['mesh']}: {skin['unweighted_vertices']} vertices carry no weight of "
                            f"'{skin['armature']}': Blender leaves them at rest, engines may not")
    owners = {ob.data.name: ob.name for ob in objects}
    numbered_per_mesh = not layouts.LAYOUTS[layout].has_index
    unlinked = [m["mesh"] for m in stats if numbered_per_mesh and "object_parent" in m.get("box_parameters", {})]
    if unlinked:
        warnings.append(f"{', '.join(unlinked)}: their objects have parent objects, but {layout} numbers boxes per "
                        "mesh, so no box names a box of another mesh as parent: export with a layout that has "
                        "box numbers (UV_FRAME, NORMAL_FRAME) for that")
    for m in stats:
        if m["transform_error"] > m.get("float32_error_bound", FILE_DECODE_TOLERANCE):
            warnings.append(f"object '{owners.get(m['mesh'], m['mesh'])}': the file's boxes decode up to "
                            f"{m['transform_error']:.2g} of the largest offset away from Blender's: the exporter "
                            "wrote positions in a space this export does not know; do not use the file")
    for m in stats:
        if m.get("stale_boxes"):
            warnings.append(f"object '{owners.get(m['mesh'], m['mesh'])}': {m['stale_boxes']} of {m['boxes']} boxes "
                            "changed shape since the bake, so the file's offsets and frames are stale and decode off: "
                            "run Bake Box Frames again, then export")
        if m.get("stale_parents"):
            warnings.append(f"object '{owners.get(m['mesh'], m['mesh'])}': {m['stale_parents']} of {m['boxes']} boxes "
                            "name parents that no box holds since the bake (boxes deleted or added, meshes joined): "
                            "the file makes them roots: run Bake Box Frames again for their parents, then export")
    return warnings


def exported_parent(ob, exported):
    """The nearest ancestor object of ``ob`` whose name is in ``exported`` (objects between are
    skipped: an empty or an armature holds no boxes), or None."""
    parent = ob.parent
    while parent is not None and parent.name_full not in exported:
        parent = parent.parent
    return parent


def _parent_meshes(objects, warnings) -> dict:
    """{mesh name: (object, parent object or None)} per mesh of ``objects``, the first object
    using the mesh deciding; a line in ``warnings`` where a later one is under an object of
    another mesh (the file holds the mesh's boxes once, so they have one parent)."""
    exported = {ob.name_full for ob in objects}
    mesh_of = lambda ob: None if ob is None else ob.data.name_full
    chosen = {}
    for ob in objects:
        up = exported_parent(ob, exported)
        first = chosen.setdefault(ob.data.name_full, (ob, up))
        if mesh_of(first[1]) != mesh_of(up):
            under = lambda o: "no object" if o is None else f"'{o.name}'"
            warnings.append(
                f"objects '{first[0].name}' and '{ob.name}' share the mesh '{ob.data.name}' but are under objects of "
                f"different meshes ({under(first[1])} and {under(up)}): the file holds the mesh's boxes once, their "
                f"parents follow '{first[0].name}'; make the mesh single-user (Object > Relations > Make Single User "
                "> Object & Data) for parents of their own")
    return chosen


def world_box_origins(ob, data: layouts.BoxData, preset, space) -> np.ndarray:
    """(boxes, 3) each box's origin in Blender's world space: box_data's ``data.box_origins``
    (target axes, in ``space``; None: ``ob``'s own) carried back."""
    local = np.asarray(data.box_origins, np.float64) / preset.length_scale @ np.linalg.inv(preset.axes).T
    if space is not None:
        return local
    matrix = np.array(ob.matrix_world, np.float64)
    return local @ matrix[:3, :3].T + matrix[:3, 3]


def link_object_parents(objects, entries, preset, layout) -> list:
    """Give the root boxes of each mesh whose object has a parent object (the nearest exported
    ancestor, exported_parent) a parent box there: the parent mesh's box whose origin lies
    nearest the box's origin in world space. Depths add down the chain of objects: a box's depth
    is its depth in its mesh plus its mesh root's depth in the file. ``entries``: (owner object,
    box_data's result, box_data's space) per mesh in export order; their data and
    stats["box_parameters"] are updated in place. CLASSIC numbers boxes per mesh, so it has no
    box of another mesh to name: its boxes keep their parents (the stats name the parent object,
    with 0 linked roots). Returns the warnings: linked duplicates under objects of different
    meshes (the first decides), and a link that would close a loop through them (left out)."""
    warnings = []
    chosen = _parent_meshes(objects, warnings)
    by_mesh = {ob.data.name_full: (ob, entry, space) for ob, entry, space in entries}
    if not layouts.LAYOUTS[layout].has_index:
        for name, (_, (_, _, stats, _), _) in by_mesh.items():
            up = chosen[name][1]
            if up is not None:
                stats["box_parameters"]["object_parent"] = {"object": up.name, "mesh": up.data.name, "linked_roots": 0}
        return warnings
    state = {}  # mesh name: "linking" while its parent mesh is being linked, then "linked"

    def link(name):
        if name in state:
            return
        state[name] = "linking"
        up = chosen[name][1]
        if up is not None and state.get(up.data.name_full) == "linking":
            warnings.append(f"object '{chosen[name][0].name}' is under '{up.name}', whose mesh's boxes are (through "
                            f"linked duplicates) below the mesh '{by_mesh[name][0].data.name}' already: that link "
                            "would make boxes their own ancestors and is left out")
        elif up is not None:
            link(up.data.name_full)
            _link_roots(by_mesh[name], by_mesh[up.data.name_full], up, preset)
        state[name] = "linked"

    for name in by_mesh:
        link(name)
    return warnings


def _link_roots(child, parent_entry, up, preset) -> None:
    """link_object_parents for one mesh: ``child`` and ``parent_entry`` are its and its parent
    object ``up``'s mesh's entries."""
    ob, (data, _, stats, _), space = child
    up_ob, (up_data, _, _, _), up_space = parent_entry
    _, parent, depth = data.box_values()
    parent, depth = parent.astype(np.int64), depth.astype(np.int64)
    row_parent = np.where(parent >= 0, parent - data.index_base, -1)
    root = np.arange(len(parent))
    for _ in range(int(depth.max()) if len(depth) else 0):
        root = np.where(row_parent[root] >= 0, row_parent[root], root)
    roots = np.flatnonzero(row_parent < 0)
    nearest = core.nearest_rows(world_box_origins(ob, data, preset, space)[roots],
                                world_box_origins(up_ob, up_data, preset, up_space))
    _, _, up_depth = up_data.box_values()
    root_depth = np.zeros(len(parent), np.int64)
    root_depth[roots] = up_depth[nearest].astype(np.int64) + 1
    parent[roots] = up_data.index_base + nearest
    data.box_parent, data.box_depth = parent.astype(np.int32), (depth + root_depth[root]).astype(np.int32)
    stats["box_parameters"] = {**box_parameter_stats(data, stats["box_parameters"]["stored"]),
                               "object_parent": {"object": up.name, "mesh": up.data.name, "linked_roots": len(roots)}}

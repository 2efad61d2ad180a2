"""Blender-facing half of the export presets: reads the baked layers, builds temporary copies of
the meshes holding the target's numbers (formats/transforms.py), runs Blender's FBX or glTF
exporter on them, and swaps the artist's meshes back. The file appears only when complete
(written under a temporary name in the same folder, then renamed)."""
from __future__ import annotations

import json
import os
import time
from typing import NamedTuple

import bpy
import numpy as np

from .. import edit_mode, mesh_io
from ..formats import files, layouts
from . import boxes, outputs_of, path_problem
from ..formats import fbx, glb, godot, import_settings, sidecar, transforms, presets
from .boxes import ExportInputError, baked_layers


# Every UV map name a layout writes (Layout.uv_names): not the artist's.
_BOXMARCH_UV_NAMES = {name for layout in layouts.LAYOUTS.values() for name in layout.uv_names}


def uv_name(layout: str, channel: str) -> str:
    """The FBX UV map name of a layout's channel "UVn" (Layout.uv_name)."""
    return layouts.LAYOUTS[layout].uv_name(channel)


def _keep_artist_uv0(copy) -> None:
    """Remove every UV map but the artist's first (made of zeros if there is none: one value per
    vertex, so it splits no vertex): the layout's channels follow it as UV1, UV2, ..."""
    artist = [uv.name for uv in copy.uv_layers if uv.name not in _BOXMARCH_UV_NAMES]
    for name in [uv.name for uv in copy.uv_layers if uv.name not in artist[:1]]:
        copy.uv_layers.remove(copy.uv_layers[name])
    if not artist:
        mesh_io.new_zero_uv(copy, "UVMap")


def _checked_box_data(mesh, preset, index_base, space, owner):
    """boxes.box_data of ``mesh`` (``space`` that of the object named ``owner``). Raises
    ExportInputError where ``space`` shears boxes."""
    data, corner_verts, stats, origins = boxes.box_data(mesh, preset, index_base, space)
    if stats["sheared_boxes"]:
        raise ExportInputError(
            f"object '{owner}': its world transform scales {stats['sheared_boxes']} of its {stats['boxes']} boxes "
            "unevenly across their axes (a non-uniform scale on a box it turns); a skinned glTF holds world "
            "positions, where those boxes are not boxes and no frame decodes them: apply the scale "
            "(Object > Apply > Scale), bake again, then export")
    return data, corner_verts, stats, origins


def _target_copy(mesh, preset, layout, data, corner_verts, stats, skin=None):
    """(copy, channels): a copy of ``mesh`` holding what the exporter must write, and the
    channels the file must hold per Blender vertex, from box_data's ``data`` (``corner_verts``
    each corner's vertex, ``stats`` its figures). glTF targets: the copy's only colour is each
    vertex's index (the channels are written into the .glb afterwards,
    glb.replace_vertex_channels); FBX targets: the channels as the copy's colour and UV maps
    (Blender's FBX exporter writes them unchanged). The copy keeps the mesh's vertex groups
    (mesh.copy()); ``skin`` (mesh_io.Skin of the object exported with it) adds the skin's figures
    to the stats."""
    index_base = data.index_base
    if skin is not None:
        spread = boxes.box_weight_spread(skin.weights, data.index - index_base, stats["boxes"])
        stats["skin"] = {"armature": skin.armature.name, "bones": list(skin.bones),
                         "non_rigid_boxes": int((spread > boxes.RIGID_WEIGHT_SPREAD).sum()),
                         "worst_weight_spread": float(spread.max()) if len(spread) else 0.0,
                         "unweighted_vertices": skin.unweighted}
    channels = layouts.channels(layout, data)
    copy = mesh.copy()
    for name in [a.name for a in copy.color_attributes]:
        copy.attributes.remove(copy.attributes[name])
    _keep_artist_uv0(copy)
    if not layouts.LAYOUTS[layout].skin_safe:  # no decode reads their normals: one per vertex splits nothing
        mesh_io.one_normal_per_vertex(copy)
    if preset.extension == ".glb":
        colour = glb.index_colours(len(data.index))
    else:
        colour = channels.get("COLOR")
        for channel in sorted(c for c in channels if c.startswith("UV")):
            name = uv_name(layout, channel)
            copy.uv_layers.new(name=name)
            # mesh_io.write_uv writes through the attribute API, which un-shares the copy's
            # arrays from the original's first (Blender 5 implicit sharing).
            mesh_io.write_uv(copy, name, transforms.uv_in_file(channels[channel][corner_verts], preset))
    if colour is not None:
        attr = copy.color_attributes.new(mesh_io.OFFSET_ATTRIBUTE, "FLOAT_COLOR", "POINT")
        attr.data.foreach_set("color", np.ascontiguousarray(colour, np.float32).reshape(-1))
        copy.color_attributes.active_color_index = 0
        copy.color_attributes.render_color_index = 0
    uv_channels = sorted(int(c[2:]) for c in channels if c.startswith("UV"))
    stats.update(layout=layout, uv_channels=uv_channels, channels=sorted(channels))
    if preset.half_float_uvs and layouts.LAYOUTS[layout].offset_in_uvs:
        stored = layouts.with_half_float_uvs(channels, [n for n in preset.half_float_uvs if n in uv_channels],
                                             preset.flip_v_on_import)
        stats["default_import_error"] = layouts.import_error(layout, channels, stored, data.half_extents)
    if preset.godot3_compression:
        stats["default_import_error"] = layouts.import_error(layout, channels, layouts.with_godot3_compression(channels),
                                                             data.half_extents)
    return copy, channels


def _operator_kwargs(operator, wanted: dict) -> dict:
    """The options this Blender's exporter knows (3.4 and 5.0 differ)."""
    known = operator.get_rna_type().properties.keys()
    return {k: v for k, v in wanted.items() if k in known}


def run_exporter(preset, layout, path):
    """Blender's exporter for ``preset``'s file extension, run on the selected objects into ``path``."""
    if preset.extension == ".fbx":
        op = bpy.ops.export_scene.fbx
        op(**_operator_kwargs(op, dict(  # tangent layers for formats/fbx.py to overwrite with the frame
            use_tspace=layouts.LAYOUTS[layout].skin_safe,
            filepath=path, use_selection=True, use_mesh_modifiers=False, axis_forward="-Z", axis_up="Y",
            bake_space_transform=True, apply_unit_scale=True, apply_scale_options="FBX_SCALE_ALL",
            colors_type="LINEAR", prioritize_active_color=True, add_leaf_bones=False, bake_anim=False)))
    else:
        op = bpy.ops.export_scene.gltf
        op(**_operator_kwargs(op, dict(
            filepath=path, export_format="GLB", use_selection=True, export_yup=True, export_apply=False,
            export_normals=not layouts.LAYOUTS[layout].skin_safe,  # those layouts write their own
            export_colors=True, export_vertex_color="ACTIVE", export_all_vertex_colors=False,
            export_active_vertex_color_when_no_material=True, export_animations=False)))


def file_channel_names(preset, layout) -> dict:
    """The name each channel ``layout`` writes (Layout.channels: the quantities' and the box
    parameters') has in the file ``preset`` writes: glTF attributes, FBX UV maps and layers, the
    .blend's own attribute and UV map names."""
    used = layouts.LAYOUTS[layout].channels
    if preset.extension == ".glb":
        return {c: f"TEXCOORD_{c[2:]}" if c.startswith("UV") else "COLOR_0" if c == "COLOR" else c for c in used}
    fbx_layers = {"COLOR": mesh_io.OFFSET_ATTRIBUTE, "NORMAL": "LayerElementNormal", "TANGENT": "LayerElementTangent"}
    names = {c: uv_name(layout, c) if c.startswith("UV") else fbx_layers[c] for c in used}
    if preset.raw_blend:  # the .blend keeps the box values in the bake's own point attributes, not UV maps
        names.update({channel: _BLEND_PARAM_ATTRIBUTES[pair] for channel, pair in
                      layouts.LAYOUTS[layout].param_channels.items()})
    return names


# The bake's stored attributes of each pair of box values (mesh_io.box_layers), as a .blend's
# sidecar names them: a FLOAT2 attribute, or two INT ones joined by "+" (x, then y).
_BLEND_PARAM_ATTRIBUTES = {("shape", "material"): mesh_io.PARAMS_LAYERS[0], ("random", "user"): mesh_io.PARAMS_LAYERS[1],
                           ("parent", "depth"): f"{mesh_io.PARENT_LAYER}+{mesh_io.DEPTH_LAYER}"}


class _Export(NamedTuple):
    """What an export writes, checked before anything is changed: the preset, the layout chosen,
    each object once, their meshes (one object per mesh), the skinned objects' skins, the files
    written (the model first) and the box table among them (None: the layout has none)."""

    preset: presets.Preset
    layout: str
    objects: list
    meshes: list
    skins: dict
    outputs: list
    table_file: str | None


def export_objects(context, objects, preset_name: str, filepath: str, layout: str | None = None) -> dict:
    """Export ``objects`` (baked meshes) with a preset (and one of its layouts; None = its
    default) to ``filepath``. Returns a report dict. Raises ExportInputError (nothing written)
    for unbaked or non-mesh objects or a layout the preset cannot carry."""
    export = _checked_export(context, objects, preset_name, filepath, layout)
    start = time.perf_counter()
    preset, layout, objects, meshes, skins, outputs, table_file = export
    warnings = mesh_io.modifier_warnings(objects, "export") + boxes.morph_warnings(objects, preset)
    if preset.extension == ".fbx" and context.scene.unit_settings.scale_length != 1.0:
        warnings.append(f"unit scale is not 1: {preset.label} will scale positions by it and the offsets will not match")

    def write(temps):
        temp = temps[outputs[0]]
        if preset.raw_blend:
            stats = [boxes.box_data(mesh, preset)[2] for mesh in meshes]  # the .blend holds the layers as they are
            bpy.data.libraries.write(temp, set(objects), fake_user=True, compress=False)
        else:
            stats, table, notes = _export_with_copies(context, objects, meshes, preset, layout, temp, skins)
            warnings.extend(notes)
            if table_file and layouts.LAYOUTS[layout].table_format == "godot3_tres":
                godot.write_image_texture_tres(temps[table_file], table)
            elif table_file:
                files.write_bytes(temps[table_file], godot.table_bin(table))
        if preset.writes_godot3_import:
            files.write_bytes(temps[import_settings.godot3_import_path(outputs[0])], import_settings.godot3_import_text())
        _write_sidecar(temps[sidecar.sidecar_path(outputs[0])], preset, layout, filepath, stats, skins)
        return stats

    stats = files.write_together(outputs, write)
    warnings += boxes.written_warnings(stats, objects, preset, layout)
    return _report(export, filepath, stats, warnings, time.perf_counter() - start)


def _checked_export(context, objects, preset_name, filepath, layout) -> _Export:
    """The export of ``objects`` to ``filepath`` with the preset named ``preset_name`` and
    ``layout`` (None: the preset's default, for a skinned export its first that skinning
    carries), or ExportInputError saying why there can be none."""
    preset = presets.PRESETS.get(preset_name)
    if preset is None:
        raise ExportInputError(f"preset must be one of {sorted(presets.PRESETS)}, got {preset_name!r}")
    problem = path_problem(filepath, preset.name)
    if problem:
        raise ExportInputError(problem)
    if layout is not None and layout not in preset.layouts:
        raise ExportInputError(f"{preset.label} carries the layouts {', '.join(preset.layouts)}, not {layout}")
    objects, meshes = _checked_meshes(objects, preset)
    skins = _skins(context, objects, preset)
    boxes.refuse_shared_world_meshes(objects, skins, preset)
    layout = _skinned_layout(preset, layout, skins)
    outputs = _checked_outputs(filepath, preset, layout)
    return _Export(preset, layout, objects, meshes, skins, outputs, sidecar.table_path(outputs[0], layout, preset.name))


def _checked_meshes(objects, preset):
    """(each object once, their meshes: one object per mesh), or ExportInputError for no objects,
    an object that is not a mesh, an unbaked mesh, or one without faces (but for a .blend)."""
    objects = list({ob.name_full: ob for ob in objects}.values())  # each object once
    if not objects:
        raise ExportInputError("no objects to export")
    for ob in objects:
        if ob.type != "MESH":
            raise ExportInputError(f"object '{ob.name}' is a {ob.type}, not a mesh")
    meshes = [ob.data for ob in mesh_io.one_object_per_mesh(objects)]
    for mesh in meshes:
        baked_layers(mesh)  # refuses unbaked meshes before anything is changed
        if not mesh.polygons and not preset.raw_blend:
            raise ExportInputError(f"mesh '{mesh.name}' has no faces (its baked layers are left from faces since "
                                   "deleted): an engine draws the boxes from faces, so the file would hold nothing")
    return objects, meshes


def _skinned_layout(preset, layout, skins) -> str:
    """``layout``, or the preset's own when None (for a skinned export its first that skinning
    carries); ExportInputError when ``skins`` is not empty and the layout keeps the frame where no
    engine's skinning moves it."""
    safe = [candidate for candidate in preset.layouts if layouts.LAYOUTS[candidate].skin_safe]
    if layout is None:
        layout = safe[0] if skins and safe else preset.layouts[0]
    if skins and not layouts.LAYOUTS[layout].skin_safe:
        name, skin = next(iter(skins.items()))
        raise ExportInputError(
            f"object '{name}' is skinned by '{skin.armature.name}': the {layout} layout keeps the box frame in UV "
            "maps, which no engine's skinning moves, so posed boxes would not decode; "
            + (f"export with the {' or '.join(safe)} layout (frame in NORMAL + TANGENT)" if safe else
               f"{preset.label} has no layout with the frame in NORMAL + TANGENT: export with the GLTF or UNITY preset"))
    return layout


def _checked_outputs(filepath, preset, layout) -> list:
    """The files the export writes (outputs_of), or ExportInputError when their folder is missing,
    one is the open .blend file or one is a folder."""
    folder = os.path.dirname(os.path.abspath(filepath))
    if not os.path.isdir(folder):
        raise ExportInputError(f"folder '{folder}' does not exist")
    outputs = outputs_of(os.path.abspath(filepath), preset.name, layout)
    for path in outputs:
        if bpy.data.filepath and files.written_path(path) == os.path.realpath(bpy.data.filepath):
            raise ExportInputError(f"'{path}' is the open .blend file: export to another path")
        if os.path.isdir(path):
            raise ExportInputError(f"'{path}' is a folder: the export writes a file there")
    return outputs


def _report(export, filepath, stats, warnings, seconds) -> dict:
    """The report export_objects returns."""
    # What the engine's default import would cost is not a warning: the export wrote what sets the
    # import (NAME.glb.import for Godot 3; the sidecar the Unity and Unreal helpers read), and
    # import_note says it once.
    default_errors = [m["default_import_error"] for m in stats if "default_import_error" in m]
    table_file = export.table_file
    return {"preset": export.preset.name, "layout": export.layout, "path": os.path.abspath(filepath),
            "skinned": _skin_summary(export.skins),
            "default_import_error": max(default_errors) if default_errors else None,
            "table": table_file,
            "table_size": list(godot.table_image_size(sum(m["boxes"] for m in stats), layouts.TABLE_PLANES))
            if table_file else None,
            "sidecar": os.path.abspath(sidecar.sidecar_path(filepath)), "files": export.outputs,
            "objects": [ob.name for ob in export.objects], "meshes": stats, "seconds": seconds,
            "warnings": warnings, "import_settings": export.preset.import_settings,
            "transform_error": max((s["transform_error"] for s in stats), default=0.0),
            "stale_boxes": sum(s.get("stale_boxes", 0) for s in stats),
            "stale_parents": sum(s.get("stale_parents", 0) for s in stats)}


def import_note(report) -> str:
    """The import settings an export needs, and what the engine's default import would cost when
    it differs: one line for the operator's report and the command line's table."""
    preset = presets.PRESETS[report["preset"]]
    note = preset.import_settings
    if report["default_import_error"]:
        note += (f" (the default import, {preset.default_import_loss}, would leave a decode error of "
                 f"{report['default_import_error']:.1e} of the half-extent)")
    return note


def _write_sidecar(path, preset, layout, filepath, stats, skins) -> None:
    """Writes the sidecar (formats/sidecar.py) of an export to ``path``."""
    text = json.dumps(sidecar.describe(preset, layout, filepath, stats, _skin_summary(skins),
                                       file_channel_names(preset, layout)), indent=2, allow_nan=False)
    files.write_bytes(path, text + "\n")


def _skin_summary(skins) -> dict:
    return {name: {"armature": skin.armature.name, "bones": list(skin.bones)} for name, skin in skins.items()}


def _skins(context, objects, preset) -> dict:
    """{object name: mesh_io.Skin} of the skinned ``objects``. Raises ExportInputError (nothing
    written) where a skin cannot be exported: an Armature modifier engines cannot carry or an
    armature outside the view layer."""
    skins = {}
    for ob in objects:
        try:
            skin = mesh_io.read_skin(ob)
        except mesh_io.SkinError as error:
            raise ExportInputError(f"object '{ob.name}': {error}") from None
        if skin is None or preset.raw_blend:  # a .blend keeps the modifier and the rig as they are
            continue
        if skin.armature.name not in context.view_layer.objects:
            raise ExportInputError(f"object '{ob.name}' is skinned by '{skin.armature.name}', which is not in the "
                                   "view layer: the exporter cannot write its bones")
        skins[ob.name] = skin
    return skins


def _fbx_frame(channels, corner_verts, preset) -> dict:
    """The NORMAL_FRAME frame per polygon corner (``corner_verts``: each corner's vertex) in the
    FBX file's axes: the channels are in the engine's frame, which the importer reaches by the
    preset's mirror (Unity negates x of positions, normals, tangents and binormals), so the file
    holds the mirror of each."""
    mirror = preset.mirror
    z = channels["NORMAL"].astype(np.float64)
    x, handedness = channels["TANGENT"][:, :3].astype(np.float64), channels["TANGENT"][:, 3:].astype(np.float64)
    y = np.cross(z, x) * handedness
    return {"NORMAL": (z * mirror)[corner_verts], "TANGENT": (x * mirror)[corner_verts],
            "BINORMAL": (y * mirror)[corner_verts]}


def _export_with_copies(context, objects, meshes, preset, layout, temp, skins):
    """Exports temporary copies of ``meshes`` in place of the originals, with the armatures of
    ``skins`` at their rest position (the file's skin binds the rest geometry); returns (stats,
    the box table of the file or None, the hierarchy's warnings: boxes.link_object_parents)."""
    copies, originals, file_channels, file_corners, stats, tables = {}, {}, {}, {}, [], []
    selection = [ob for ob in context.view_layer.objects if ob.select_get()]
    active = context.view_layer.objects.active
    users = {}
    owner_of_mesh = {ob.data.as_pointer(): ob for ob in mesh_io.one_object_per_mesh(objects)}
    armatures = list({skin.armature.name: skin.armature for skin in skins.values()}.values())
    pose_positions = {rig.name: rig.data.pose_position for rig in armatures}
    truths = {}
    try:
        for rig in armatures:
            rig.data.pose_position = "REST"
        context.view_layer.update()  # world matrices at rest: an object parented to a bone moves with it
        box_data, entries = {}, []
        for mesh in meshes:
            ob = owner_of_mesh[mesh.as_pointer()]
            # box numbers run on across the file's meshes (CLASSIC has none: each mesh from 0)
            index_base = sum(len(e[1][0].box_half_extents) for e in entries) if layouts.LAYOUTS[layout].has_index else 0
            space = boxes.written_space(ob, skins.get(ob.name), preset)
            box_data[mesh.as_pointer()] = _checked_box_data(mesh, preset, index_base, space, ob.name)
            entries.append((ob, box_data[mesh.as_pointer()], space))
        hierarchy_warnings = boxes.link_object_parents(objects, entries, preset, layout)
        for mesh in meshes:
            ob = owner_of_mesh[mesh.as_pointer()]
            data, corner_verts, mesh_stats, origins = box_data[mesh.as_pointer()]
            copy, channels = _target_copy(mesh, preset, layout, data, corner_verts, mesh_stats, skins.get(ob.name))
            copies[mesh.as_pointer()] = copy  # removed in the finally below, whatever happens next
            if "TABLE" in channels:
                tables.append(channels.pop("TABLE"))
            name = mesh.name
            if mesh.library is None:  # a linked mesh cannot be renamed, nor does its copy need it:
                mesh.name = name + ".boxmarch-original"  # the copy is local, a name of its own
                originals[name] = mesh
            copy.name = name  # the file names the mesh as the artist did
            name = copy.name  # (a local mesh of a linked one's name keeps it: the copy then gets another)
            file_channels[name], file_corners[name] = channels, corner_verts
            truths[name] = (origins, mesh_stats)
            stats.append(mesh_stats)
        for ob in objects:
            users[ob.name] = ob.data
            ob.data = copies[ob.data.as_pointer()]
        edit_mode.select_only(context.view_layer, objects + armatures)  # a selected armature exports its skin
        run_exporter(preset, layout, temp)
        if not os.path.exists(temp):
            raise RuntimeError(f"the {preset.label} exporter wrote nothing")
        if preset.extension == ".glb":
            gltf, binary = glb.read(temp)
            for name, (origins, mesh_stats) in truths.items():
                mesh_stats["transform_error"], mesh_stats["float32_error_bound"] = boxes.file_decode_error(
                    gltf, binary, name, layout, file_channels[name], origins)
            gltf, binary = glb.replace_vertex_channels(gltf, binary, file_channels)
            glb.write(temp, gltf, binary)
        elif layouts.LAYOUTS[layout].skin_safe:
            fbx.replace_frame(temp, {name: _fbx_frame(channels, file_corners[name], preset)
                                     for name, channels in file_channels.items()})
    finally:
        for rig in armatures:
            rig.data.pose_position = pose_positions[rig.name]
        for ob in objects:
            if ob.name in users:
                ob.data = users[ob.name]
        for copy in copies.values():
            bpy.data.meshes.remove(copy)
        for name, mesh in originals.items():
            mesh.name = name
        for ob in context.view_layer.objects:
            ob.select_set(ob in selection)
        context.view_layer.objects.active = active
    return stats, (np.concatenate(tables) if tables else None), hierarchy_warnings

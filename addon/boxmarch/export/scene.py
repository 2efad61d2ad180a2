"""Blender-facing half of the export presets: reads the baked layers, builds temporary copies of
the meshes holding the target's numbers (export/transforms.py), runs Blender's FBX or glTF
exporter on them, and swaps the artist's meshes back. The file appears only when complete
(written under a temporary name in the same folder, then renamed)."""
from __future__ import annotations

import os
import time

import bpy
import numpy as np

from .. import core, mesh_io
from . import glb, transforms


class ExportInputError(ValueError):
    """The selection cannot be exported as it is; the message says why. Nothing was written."""


def baked_layers(mesh):
    """(offsets float32 (vertices, 4) as the shader reads them, quat_xy, quat_zw float32
    (corners, 2), corner_verts) of a baked mesh. Raises ExportInputError when it is not baked."""
    missing = [name for name in (mesh_io.QUAT_XY_UV, mesh_io.QUAT_ZW_UV) if name not in mesh.uv_layers]
    attr = mesh.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE)
    if attr is None:
        missing.insert(0, mesh_io.OFFSET_ATTRIBUTE)
    if missing:
        raise ExportInputError(f"mesh '{mesh.name}' is not baked (no {', '.join(missing)}): run Bake Box Frames first")
    _, _, _, corner_verts = mesh_io.read_topology(mesh)
    settings = mesh_io.BakeSettings(encoding=attr.data_type)
    offsets = mesh_io._read_offsets(mesh, settings, corner_verts, len(mesh.vertices))
    if offsets.dtype == np.uint8:
        offsets = offsets.astype(np.float32) / np.float32(255.0)
    corners = len(corner_verts)
    return (offsets, mesh_io._read_uv(mesh, mesh_io.QUAT_XY_UV, corners),
            mesh_io._read_uv(mesh, mesh_io.QUAT_ZW_UV, corners), corner_verts)


def _target_copy(mesh, preset, index_colour: bool):
    """A copy of ``mesh`` whose only colour attribute is BoxOffset in the target's numbers (or,
    for glTF, each vertex's index, replaced in the file afterwards) and whose quaternion UV maps
    hold the target's quaternion as the exporter must receive it. Returns (copy, offsets the file
    must hold per vertex, stats)."""
    offsets, quat_xy, quat_zw, corner_verts = baked_layers(mesh)
    q = np.concatenate([quat_xy, quat_zw], axis=1)
    target_q = transforms.target_quaternions(q, preset).astype(np.float32)
    target_rgba = transforms.target_offsets(offsets, preset)
    # Self-check, per vertex (the baked quaternion is the same on every corner of a vertex): the
    # decode in the target frame must land where the target frame puts Blender's decode.
    positions = mesh_io.read_positions(mesh).astype(np.float64)
    vertex_q = np.zeros((len(positions), 4), np.float32)
    vertex_q[corner_verts] = q
    vertex_target_q = np.zeros((len(positions), 4), np.float32)
    vertex_target_q[corner_verts] = target_q
    f = core.decode_offsets(offsets)
    blender_origin = positions + core.rotate_vector(f, vertex_q)
    target_origin = (transforms.target_positions(positions, preset)
                     + core.rotate_vector(core.decode_offsets(target_rgba), vertex_target_q))
    reach = max(float(np.abs(f).max()) if len(f) else 0.0, 1e-30)
    error = float(np.abs(target_origin - transforms.target_positions(blender_origin, preset)).max() / reach)

    copy = mesh.copy()
    for name in [a.name for a in copy.color_attributes]:
        copy.attributes.remove(copy.attributes[name])
    colour = copy.color_attributes.new(mesh_io.OFFSET_ATTRIBUTE, "FLOAT_COLOR", "POINT")
    colour.data.foreach_set("color", (glb.index_colours(len(mesh.vertices)) if index_colour else target_rgba).reshape(-1))
    copy.color_attributes.active_color_index = 0
    copy.color_attributes.render_color_index = 0
    # mesh_io._write_uv writes through the attribute API, which un-shares the copy's arrays from
    # the original's first (Blender 5 implicit sharing).
    mesh_io._write_uv(copy, mesh_io.QUAT_XY_UV, transforms.uv_for_exporter(target_q[:, :2], preset))
    mesh_io._write_uv(copy, mesh_io.QUAT_ZW_UV, transforms.uv_for_exporter(target_q[:, 2:], preset))
    names = [uv.name for uv in copy.uv_layers]
    stats = {"mesh": mesh.name, "vertices": len(mesh.vertices), "corners": len(corner_verts),
             "uv_channels": [names.index(mesh_io.QUAT_XY_UV), names.index(mesh_io.QUAT_ZW_UV)],
             "colour": mesh.color_attributes[mesh_io.OFFSET_ATTRIBUTE].data_type,
             "max_alpha": float(target_rgba[:, 3].max()) if len(target_rgba) else 0.0,
             "transform_error": error}
    return copy, target_rgba, stats


def _operator_kwargs(operator, wanted: dict) -> dict:
    """The options this Blender's exporter knows (3.4 and 5.0 differ)."""
    known = operator.get_rna_type().properties.keys()
    return {k: v for k, v in wanted.items() if k in known}


def _run_exporter(preset, path):
    if preset.name == "UNITY":
        op = bpy.ops.export_scene.fbx
        op(**_operator_kwargs(op, dict(
            filepath=path, use_selection=True, use_mesh_modifiers=False, axis_forward="-Z", axis_up="Y",
            bake_space_transform=True, apply_unit_scale=True, apply_scale_options="FBX_SCALE_ALL",
            colors_type="LINEAR", prioritize_active_color=True, add_leaf_bones=False, bake_anim=False)))
    else:
        op = bpy.ops.export_scene.gltf
        op(**_operator_kwargs(op, dict(
            filepath=path, export_format="GLB", use_selection=True, export_yup=True, export_apply=False,
            export_colors=True, export_vertex_color="ACTIVE", export_all_vertex_colors=False,
            export_active_vertex_color_when_no_material=True, export_animations=False)))


def export_objects(context, objects, preset_name: str, filepath: str) -> dict:
    """Export ``objects`` (baked meshes) with a preset to ``filepath``. Returns a report dict.
    Raises ExportInputError (nothing written) for unbaked or non-mesh objects."""
    preset = transforms.PRESETS.get(preset_name)
    if preset is None:
        raise ExportInputError(f"preset must be one of {sorted(transforms.PRESETS)}, got {preset_name!r}")
    objects = list({ob.name_full: ob for ob in objects}.values())  # each object once
    if not objects:
        raise ExportInputError("no objects to export")
    if bpy.data.filepath and os.path.abspath(filepath) == os.path.abspath(bpy.data.filepath):
        raise ExportInputError(f"'{filepath}' is the open .blend file: export to another path")
    for ob in objects:
        if ob.type != "MESH":
            raise ExportInputError(f"object '{ob.name}' is a {ob.type}, not a mesh")
    meshes = list({ob.data.name_full: ob.data for ob in objects}.values())
    for mesh in meshes:
        baked_layers(mesh)  # refuses unbaked meshes before anything is changed
    start = time.perf_counter()
    folder = os.path.dirname(os.path.abspath(filepath))
    if not os.path.isdir(folder):
        raise ExportInputError(f"folder '{folder}' does not exist")
    temp = os.path.join(folder, f".{os.path.basename(filepath)}.boxmarch-partial{preset.extension}")
    warnings = mesh_io.modifier_warnings(objects, "export")
    if preset.name == "UNITY" and context.scene.unit_settings.scale_length != 1.0:
        warnings.append("unit scale is not 1: Unity will scale positions by it and the offsets will not match")
    try:
        if preset.name == "BLENDER":
            stats = [{"mesh": mesh.name, "vertices": len(mesh.vertices), "transform_error": 0.0} for mesh in meshes]
            bpy.data.libraries.write(temp, set(objects), fake_user=True, compress=False)
        else:
            stats = _export_with_copies(context, objects, meshes, preset, temp)
            if preset.name == "UNITY":
                floats = [m for m in stats if m["colour"] == "FLOAT_COLOR"]
                if floats:
                    warnings.append(
                        f"{', '.join(m['mesh'] for m in floats)}: float offsets (alpha up to "
                        f"{max(m['max_alpha'] for m in floats):.3g}); Unity usually stores vertex colours as "
                        "8-bit Color32, which clips alpha above 1 and rounds the rest: bake with 8-bit colour "
                        "for Unity (docs/EXPORT.md)")
        os.replace(temp, filepath)
    finally:
        if os.path.exists(temp):
            os.remove(temp)
    return {"preset": preset.name, "path": os.path.abspath(filepath), "objects": [ob.name for ob in objects],
            "meshes": stats, "seconds": time.perf_counter() - start, "warnings": warnings,
            "transform_error": max((s["transform_error"] for s in stats), default=0.0)}


def _export_with_copies(context, objects, meshes, preset, temp):
    index_colour = preset.name == "GLTF"
    copies, originals, file_colours, stats = {}, {}, {}, []
    selection = [ob for ob in context.view_layer.objects if ob.select_get()]
    active = context.view_layer.objects.active
    users = {}
    try:
        for mesh in meshes:
            copy, rgba, mesh_stats = _target_copy(mesh, preset, index_colour)
            name = mesh.name
            mesh.name = name + ".boxmarch-original"
            copy.name = name  # the file names the mesh as the artist did
            copies[mesh.as_pointer()], originals[name], file_colours[name] = copy, mesh, rgba
            stats.append(mesh_stats)
        for ob in objects:
            users[ob.name] = ob.data
            ob.data = copies[ob.data.as_pointer()]
        for ob in selection:
            ob.select_set(False)
        for ob in objects:
            ob.select_set(True)
        context.view_layer.objects.active = objects[0]
        _run_exporter(preset, temp)
        if not os.path.exists(temp):
            raise RuntimeError(f"the {preset.label} exporter wrote nothing")
        if index_colour:
            gltf, binary = glb.read(temp)
            gltf, binary = glb.replace_index_colours(gltf, binary, file_colours)
            glb.write(temp, gltf, binary)
    finally:
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
    return stats

"""The files an export writes beside its model, and the sidecar ``NAME.boxmarch.json`` that tells
an engine-side helper (Godot plug-in, Unity postprocessor, three.js loader, Unreal script) what the
model holds: layout, channel of every quantity, axes and units, box count, skinning, the import
settings the engine needs and the decode error the export measured. Blender-free.

``sidecar.schema.json`` beside this module is the JSON Schema of the sidecar (docs/FORMAT.md);
the keys ``format_version``, ``preset``, ``layout``, ``skinned`` and ``box_count`` are the ones
every helper reads first, and keep their names and types across format versions.
"""
from __future__ import annotations

import os

import numpy as np

from . import import_settings, layouts
from .godot import TABLE_WIDTH as GODOT3_TABLE_WIDTH
from .godot import table_image_size
from .presets import PRESETS

FORMAT_VERSION = 1
SIDECAR_SUFFIX = ".boxmarch.json"
SCHEMA_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sidecar.schema.json")

# Where each layout keeps each quantity, by channel ("UVn" = the n-th UV map after the artist's
# UV0, "COLOR", "NORMAL", "TANGENT", "TABLE" = the box table texel of the vertex's index):
# Layout.quantities; docs/ENGINES.md states the decode.
QUANTITIES = {name: layout.quantities for name, layout in layouts.LAYOUTS.items()}

def box_parameter_channels(layout: str) -> dict:
    """Where ``layout`` keeps each per-box parameter and the hierarchy: a vertex channel
    ("UV5.x") where it has room (Layout.param_channels and parent_channel), else the box table's
    texel ("TABLE.1.b": plane 1, blue) where the layout has one (Layout.has_table)."""
    spec = layouts.layout_named(layout)
    found = {name: f"{channel}.{component}" for channel, names in spec.param_channels.items()
             for component, name in zip("xy", names)}
    if spec.parent_channel:
        found["parent"] = spec.parent_channel
    if spec.has_table:
        for plane, names in enumerate(layouts.TABLE_PLANE_CONTENTS):
            for component, name in zip("rgba", names):
                if name in ("shape", "material", "random", "user", "parent", "depth"):
                    found.setdefault(name, f"TABLE.{plane}.{component}")
    return {name: found[name] for name in ("shape", "material", "random", "user", "parent", "depth")}


def sidecar_path(filepath: str) -> str:
    """``NAME.boxmarch.json`` beside ``filepath`` (NAME: its stem)."""
    return os.path.splitext(filepath)[0] + SIDECAR_SUFFIX


TABLE_SUFFIXES = {"godot3_tres": ".boxes.tres", "float32_rgba": ".boxes.bin"}  # by Layout.table_format


def table_path(filepath: str, layout: str = "NORMAL_COLOR", preset_name: str = "GODOT3") -> str | None:
    """Where a layout's box table goes, beside the file, by its Layout.table_format:
    ``NAME.boxes.tres`` (NORMAL_COLOR, for Godot 3), ``NAME.boxes.bin``; None for CLASSIC (no
    index) and the BLENDER preset (the .blend holds the layers themselves)."""
    table_format = layouts.layout_named(layout).table_format
    if not table_format or PRESETS[preset_name].raw_blend:
        return None
    return os.path.splitext(filepath)[0] + TABLE_SUFFIXES[table_format]


def written_beside(filepath: str, preset_name: str, layout: str) -> list[str]:
    """Every file an export of ``preset_name`` in ``layout`` writes besides ``filepath``: the
    sidecar, the box table of a layout that has one (:func:`table_path`), Godot 3's import
    settings (``NAME.glb.import``)."""
    paths = [sidecar_path(filepath)]
    table = table_path(filepath, layout, preset_name)
    if table:
        paths.append(table)
    if PRESETS[preset_name].writes_godot3_import:
        paths.append(import_settings.godot3_import_path(filepath))
    return paths


def data_from_file(preset) -> np.ndarray:
    """(3, 3) matrix taking positions as the file holds them to the frame the box data are
    expressed in (the engine's object frame after its importer), units included."""
    return preset.axes @ preset.file_from_blender.T * preset.length_scale


def describe(preset, layout: str, filepath: str, stats: list, skins: dict, file_channel_names: dict) -> dict:
    """The sidecar of an export of ``stats`` (per mesh, export.boxes.box_data's) to ``filepath``
    with ``preset`` (presets.Preset) in ``layout``; ``skins``: {object: {"armature", "bones"}}
    of the skinned objects; ``file_channel_names``: the name each channel has in the file ("UV1"
    -> "TEXCOORD_1" or an FBX UV map name)."""
    spec = layouts.layout_named(layout)
    quantities = {name: dict(q) for name, q in spec.quantities.items()}
    if quantities.get("half_extents", {}).get("encoding") == "box_table":
        quantities["half_extents"].update(file=os.path.basename(table_path(filepath, layout)),
                                          texels_per_row=GODOT3_TABLE_WIDTH)
    default_errors = [m["default_import_error"] for m in stats if "default_import_error" in m]
    box_count = int(sum(m["boxes"] for m in stats))
    table = table_path(filepath, layout, preset.name)
    table_width, table_height = table_image_size(box_count, layouts.TABLE_PLANES)
    return {
        "format_version": FORMAT_VERSION,
        "preset": preset.name,
        "layout": layout,
        "skinned": bool(skins),
        "box_count": box_count,
        "file": os.path.basename(filepath),
        "vertex_count": int(sum(m["vertices"] for m in stats)),
        "meshes": [{"name": m["mesh"], "vertices": int(m["vertices"]), "boxes": int(m["boxes"])} for m in stats],
        "skins": skins,
        "quantities": quantities,
        "box_parameters": box_parameter_channels(layout),
        "box_table": None if table is None else {
            "file": os.path.basename(table), "format": spec.table_format,
            "planes": layouts.TABLE_PLANE_CONTENTS, "width": table_width, "height": table_height},
        "file_channels": file_channel_names,
        "axes": {"file": preset.file_frame, "data": preset.data_frame,
                 "data_from_file": data_from_file(preset).tolist(), "length_scale": preset.length_scale,
                 "v_flipped_in_file": preset.flip_v_on_import},
        "import_settings": {"text": preset.import_settings, "settings": preset.engine_settings,
                            "helper": preset.helper},
        "decode_error": {"export": max((float(m["transform_error"]) for m in stats), default=0.0),
                         "default_import": max(default_errors) if default_errors else None},
    }

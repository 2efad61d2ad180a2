"""Engine export presets. ``transforms`` and ``glb`` are Blender-free (format-facing);
``scene`` drives Blender's exporters. docs/EXPORT.md derives and measures every transform."""
from __future__ import annotations

import os

from .transforms import PRESETS


def table_path(filepath: str) -> str:
    """Where the NORMAL_COLOR layout's box table goes: beside the file, ``NAME.boxes.tres``."""
    return os.path.splitext(filepath)[0] + ".boxes.tres"


def outputs_of(filepath: str, preset_name: str, layout: str | None = None) -> list:
    """Every file an export to ``filepath`` writes, the exported file first: the one list the
    export writes (scene.export_objects) and the command line checks before anything is written.
    ``layout`` None: any layout the preset may choose (a skinned export picks its own)."""
    candidates = [layout] if layout else PRESETS[preset_name].layouts
    paths = [filepath]
    if "NORMAL_COLOR" in candidates:
        paths.append(table_path(filepath))
    return paths

"""The Blender-facing half of the engine export: ``scene`` drives Blender's exporters, ``boxes``
reads a baked mesh's box data, ``every_engine`` exports once per engine preset; ``outputs_of``
lists the files an export writes. What the files hold is the Blender-free ``formats`` package's.
docs/EXPORT.md derives and measures every transform."""
from __future__ import annotations

import os

from ..formats import sidecar
from ..formats.presets import PRESETS


def path_problem(filepath: str, preset_name: str) -> str | None:
    """Why ``filepath`` cannot be the file an export with ``preset_name`` writes, or None: its
    name must end in the preset's extension (any case) with a name before it (Blender's exporters
    would add the extension themselves to ".glb" or "model", and write another file than the one
    checked and renamed)."""
    extension = PRESETS[preset_name].extension
    name = os.path.basename(filepath)
    if not name.lower().endswith(extension):
        return f"the {PRESETS[preset_name].label} preset writes a {extension} file: the path must end in " \
               f"{extension}, got '{filepath}'"
    if len(name) == len(extension):
        return f"'{filepath}' has no file name before {extension}: name the file, e.g. 'model{extension}'"
    return None


def outputs_of(filepath: str, preset_name: str, layout: str | None = None) -> list:
    """Every file an export to ``filepath`` writes, the exported file first (then the sidecar, the
    box table, Godot 3's import settings: sidecar.written_beside): the one list the
    export writes (scene.export_objects) and the command line checks before anything is written.
    ``layout`` None: any layout the preset may choose (a skinned export picks its own)."""
    candidates = [layout] if layout else PRESETS[preset_name].layouts
    paths = dict.fromkeys([filepath])
    for each in candidates:
        paths.update(dict.fromkeys(sidecar.written_beside(filepath, preset_name, each)))
    return list(paths)

"""The Blender-facing half of the engine export: ``scene`` drives Blender's exporters, ``boxes``
reads a baked mesh's box data, ``every_engine`` exports once per engine preset; ``outputs_of``
lists the files an export writes. What the files hold is the Blender-free ``formats`` package's.
docs/EXPORT.md derives and measures every transform."""
from __future__ import annotations

from ..formats import sidecar
from ..formats.presets import PRESETS


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

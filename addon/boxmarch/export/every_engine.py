"""One export per engine preset of the same baked objects (the demo's engine files)."""
from __future__ import annotations

import os

from . import scene, transforms

ENGINE_PRESETS = ("GLTF", "GODOT3", "UNITY", "UNREAL")


def export_every_engine(context, objects, folder: str, stem: str) -> list:
    """Exports ``objects`` with every engine preset's default layout to
    ``folder/STEM_<preset>.<ext>`` (each with its box table beside it: STEM_<preset>.boxes.tres or .bin). Returns the
    export reports in ENGINE_PRESETS order; raises scene.ExportInputError before writing
    anything for objects no preset can export."""
    reports = []
    for name in ENGINE_PRESETS:
        preset = transforms.PRESETS[name]
        path = os.path.join(folder, f"{stem}_{name.lower()}{preset.extension}")
        reports.append(scene.export_objects(context, objects, name, path))
    return reports

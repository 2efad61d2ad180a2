"""One export per engine preset of the same baked objects (the demo's engine files)."""
from __future__ import annotations

import os

from . import outputs_of, scene
from ..formats.presets import PRESETS

ENGINE_PRESETS = tuple(name for name, preset in PRESETS.items() if not preset.raw_blend)


def engine_path(folder: str, stem: str, preset_name: str) -> str:
    """Where ``export_every_engine`` writes a preset's file: ``folder/STEM.glb`` for GLTF (the
    glTF file itself), ``folder/STEM_<preset>.<ext>`` for the others."""
    preset = PRESETS[preset_name]
    suffix = "" if preset_name == "GLTF" else f"_{preset_name.lower()}"
    return os.path.join(folder, f"{stem}{suffix}{preset.extension}")


def engine_outputs(folder: str, stem: str, presets=ENGINE_PRESETS) -> list:
    """Every file ``export_every_engine`` writes (each preset's box table and sidecar beside it too)."""
    return [path for name in presets for path in outputs_of(engine_path(folder, stem, name), name)]


def export_every_engine(context, objects, folder: str, stem: str, presets=ENGINE_PRESETS) -> list:
    """Exports ``objects`` with each of ``presets``' default layout to ``engine_path``. Returns
    the export reports in ``presets`` order; raises scene.ExportInputError before writing
    anything for objects no preset can export."""
    return [scene.export_objects(context, objects, name, engine_path(folder, stem, name)) for name in presets]

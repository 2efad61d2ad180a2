"""Engine export presets. ``transforms`` and ``glb`` are Blender-free (format-facing);
``scene`` drives Blender's exporters. docs/EXPORT.md derives and measures every transform."""
from .transforms import PRESETS  # noqa: F401

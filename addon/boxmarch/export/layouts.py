"""The engine layouts, under the import path the export code has always used: they live in
boxmarch/layouts.py (Blender-free, shared by the export presets and the viewport preview)."""
from ..layouts import LAYOUTS, BoxData, Layout, channels, frame_axes, half_float_error, to_origin  # noqa: F401

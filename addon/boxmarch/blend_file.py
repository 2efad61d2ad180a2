"""Saving the open .blend file as a copy, atomically (formats.files.write_atomically)."""
from __future__ import annotations

import bpy

from .formats import files


def save_blend_copy(path: str) -> str:
    """Save the open file as a copy at ``path`` (the open file keeps its own path), atomically."""
    return files.write_atomically(path, lambda temp: bpy.ops.wm.save_as_mainfile(filepath=temp, copy=True,
                                                                                check_existing=False))

"""Files that appear only complete: written under a temporary name in the same folder, then
renamed over the target (one rename on one filesystem, so a reader never sees half a file)."""
from __future__ import annotations

import os


def partial_path(path: str) -> str:
    """The temporary name ``path`` is written under: hidden, beside it, same extension."""
    folder, name = os.path.split(os.path.abspath(path))
    root, ext = os.path.splitext(name)
    return os.path.join(folder, f".{root}.boxmarch-partial{ext}")


def write_atomically(path: str, write) -> str:
    """Call write(temporary path), then rename it onto ``path``; on failure remove the temporary
    file and leave ``path`` as it was. Returns the absolute path written. The folder must exist
    (FileNotFoundError names it otherwise)."""
    path = os.path.abspath(path)
    folder = os.path.dirname(path)
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"folder '{folder}' does not exist")
    temp = partial_path(path)
    try:
        write(temp)
        os.replace(temp, path)
    finally:
        if os.path.exists(temp):
            os.remove(temp)
    return path


def save_blend_copy(path: str) -> str:
    """Save the open file as a copy at ``path`` (the open file keeps its own path), atomically."""
    import bpy

    return write_atomically(path, lambda temp: bpy.ops.wm.save_as_mainfile(filepath=temp, copy=True,
                                                                           check_existing=False))

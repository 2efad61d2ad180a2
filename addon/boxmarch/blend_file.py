"""Saving the open .blend file as a copy, atomically (formats.files.write_atomically)."""
from __future__ import annotations

import os

import bpy

from .formats import files

ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
# Blender's compressed .blend (3.0 on) is seekable zstd: its last bytes are the seek table's magic.
ZSTD_SEEK_TABLE_MAGIC = b"\xb1\xea\x92\x8f"


def is_whole_blend(path: str) -> bool:
    """Whether the .blend file at ``path`` ends as Blender ends a whole one: an uncompressed file
    with its ENDB block, a compressed one with its zstd seek table. Blender 5.0's compressed save
    reports no error when a write fails (a full disk, a file-size limit) and leaves a cut file."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(len(ZSTD_MAGIC))
        f.seek(max(size - 64, 0))
        tail = f.read()
    if head == ZSTD_MAGIC:
        return tail.endswith(ZSTD_SEEK_TABLE_MAGIC)
    return head == b"BLEN" and b"ENDB" in tail


def save_blend_copy(path: str) -> str:
    """Save the open file as a copy at ``path`` (the open file keeps its own path), atomically.
    Raises OSError, leaving ``path`` as it was, where the file Blender wrote is not whole."""
    def save(temp):
        bpy.ops.wm.save_as_mainfile(filepath=temp, copy=True, check_existing=False)
        if not is_whole_blend(temp):
            raise OSError(f"Blender could not write the whole of '{path}' (is the disk full, or a file-size limit "
                          "reached?): the file is left as it was")
    return files.write_atomically(path, save)

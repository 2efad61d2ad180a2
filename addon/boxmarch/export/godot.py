"""The NORMAL_COLOR layout's box table as a Godot 3 text resource (.tres). Blender-free.

Godot 3's glTF importer keeps two UV sets, so the half-extents of every box travel as a float
texture, one RGBA texel per box number (Unreal's Pivot Painter carries per-element data the same
way). An ImageTexture resource with an embedded ``RGBAFloat`` image keeps the float32 bits
exactly (an imported .exr would pass through Godot's image importer); flags 0: no filtering,
mipmaps or repeat. The shader reads texel (index % width, index / width) with texelFetch.
"""
from __future__ import annotations

import numpy as np

TABLE_WIDTH = 4096  # texels per row: Godot 3 textures may be up to 16384 wide


def table_size(boxes: int) -> tuple[int, int]:
    """(width, height) in texels of the table of ``boxes`` boxes (at least 1 x 1)."""
    width = min(max(boxes, 1), TABLE_WIDTH)
    return width, -(-max(boxes, 1) // width)


def image_texture_tres(table) -> str:
    """Text of a Godot 3 ImageTexture resource holding ``table`` (boxes, 4) as float32 RGBA
    texels, row by row, the rest of the last row zero."""
    table = np.asarray(table, np.float32).reshape(-1, 4)
    width, height = table_size(len(table))
    texels = np.zeros((width * height, 4), "<f4")
    texels[:len(table)] = table
    data = ", ".join(map(str, texels.tobytes()))
    return (f'[gd_resource type="ImageTexture" load_steps=2 format=2]\n\n'
            f'[sub_resource type="Image" id=1]\n'
            f'data = {{\n"data": PoolByteArray( {data} ),\n"format": "RGBAFloat",\n"height": {height},\n'
            f'"mipmaps": false,\n"width": {width}\n}}\n\n'
            f'[resource]\nflags = 0\nimage = SubResource( 1 )\nsize = Vector2( {width}, {height} )\n')

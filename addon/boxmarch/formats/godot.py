"""The box table as a Godot 3 text resource (.tres, the NORMAL_COLOR layout) or raw float32
texels (.bin, the other layouts with an index). Blender-free.

Godot 3's glTF importer keeps two UV sets, so the half-extents of every box travel as a float
texture, one RGBA texel per box number and plane (Unreal's Pivot Painter carries per-element data
the same way): plane 0 = (h, parent), plane 1 = (shape, material, random, user), plane 2 =
(depth, 0, 0, 0), plane 3 = (origin, 0), plane 4 = the frame's quaternion (layouts.box_table).
An ImageTexture resource with an embedded ``RGBAFloat`` image keeps the float32 bits exactly (an
imported .exr would pass through Godot's image importer); flags 0: no filtering, mipmaps or
repeat. The shader reads texel (index % width, plane * height / 5 + index / width) with
texelFetch.
"""
from __future__ import annotations

import numpy as np

TABLE_WIDTH = 4096  # texels per row: Godot 3 textures may be up to 16384 wide


def table_size(boxes: int) -> tuple[int, int]:
    """(width, height) in texels of the table of ``boxes`` boxes (at least 1 x 1)."""
    width = min(max(boxes, 1), TABLE_WIDTH)
    return width, -(-max(boxes, 1) // width)


def table_image_size(boxes: int, planes: int) -> tuple[int, int]:
    """(width, height) in texels of :func:`table_image` of ``boxes`` boxes of ``planes`` planes."""
    width, height = table_size(boxes)
    return width, planes * height


def table_image(table) -> np.ndarray:
    """float32 (planes * height, width, 4): the box table ``table`` ((boxes, planes, 4), or
    (boxes, 4) for one plane) as an image, plane after plane, each plane starting on a new row:
    box i's texel of plane k sits at (x, y) = (i % width, k * height + i // width), the rest of
    each plane's last row zero."""
    table = np.asarray(table, np.float32)
    table = table.reshape(len(table), -1, 4)
    boxes, planes = table.shape[0], table.shape[1]
    width, height = table_size(boxes)
    image = np.zeros((planes, width * height, 4), np.float32)
    image[:, :boxes] = table.transpose(1, 0, 2)
    return image.reshape(planes * height, width, 4)


def image_texture_tres(table) -> str:
    """Text of a Godot 3 ImageTexture resource holding the box table ``table`` (see
    :func:`table_image`) as float32 RGBA texels, row by row."""
    image = table_image(table)
    height, width = image.shape[:2]
    data = ", ".join(map(str, image.astype("<f4").tobytes()))
    return (f'[gd_resource type="ImageTexture" load_steps=2 format=2]\n\n'
            f'[sub_resource type="Image" id=1]\n'
            f'data = {{\n"data": PoolByteArray( {data} ),\n"format": "RGBAFloat",\n"height": {height},\n'
            f'"mipmaps": false,\n"width": {width}\n}}\n\n'
            f'[resource]\nflags = 0\nimage = SubResource( 1 )\nsize = Vector2( {width}, {height} )\n')


def table_bin(table) -> bytes:
    """The box table as raw little-endian float32 RGBA texels of :func:`table_image`, row by row,
    preceded by nothing (width = min(boxes, TABLE_WIDTH), height from the size): what Unity's
    Texture2D.LoadRawTextureData (RGBAFloat) or a three.js DataTexture (RGBA, FloatType) take."""
    return table_image(table).astype("<f4").tobytes()

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


# Bytes of the table turned into text at a time: the text of one chunk (up to 5 characters a byte)
# stays a few tens of MiB, whatever the table's size.
TEXT_CHUNK_BYTES = 1 << 22


def write_image_texture_tres(path, table) -> None:
    """Write to ``path`` a Godot 3 ImageTexture resource holding the box table ``table`` (see
    :func:`table_image`) as float32 RGBA texels, row by row: the image's bytes as the decimal
    list of a PoolByteArray, written chunk by chunk (TEXT_CHUNK_BYTES)."""
    image = table_image(table)
    height, width = image.shape[:2]
    data = np.ascontiguousarray(image, "<f4").reshape(-1).view(np.uint8)
    with open(path, "wb") as f:
        f.write(b'[gd_resource type="ImageTexture" load_steps=2 format=2]\n\n'
                b'[sub_resource type="Image" id=1]\n'
                b'data = {\n"data": PoolByteArray( ')
        for start in range(0, len(data), TEXT_CHUNK_BYTES):
            f.write(_decimal_list(data[start:start + TEXT_CHUNK_BYTES], last=start + TEXT_CHUNK_BYTES >= len(data)))
        f.write(f' ),\n"format": "RGBAFloat",\n"height": {height},\n'
                f'"mipmaps": false,\n"width": {width}\n}}\n\n'
                f'[resource]\nflags = 0\nimage = SubResource( 1 )\nsize = Vector2( {width}, {height} )\n'.encode())


# Each byte value's text and separator, "0, " .. "255, ", left-aligned in 5 bytes (zeros after);
# and each pair of bytes' texts one after the other in 10: _decimal_list gathers the rows of a
# chunk's byte pairs and keeps the non-zero bytes (half as many rows as bytes: faster).
_BYTE_TEXT = np.array([list(f"{v}, ".encode().ljust(5, b"\0")) for v in range(256)], np.uint8)


def _pair_text() -> np.ndarray:
    pairs = np.zeros((256, 256, 10), np.uint8)
    pairs[:, :, :5] = _BYTE_TEXT[:, None, :]
    for length in (3, 4, 5):  # the first text's length: the second follows it
        pairs[(_BYTE_TEXT != 0).sum(axis=1) == length, :, length:length + 5] = _BYTE_TEXT
    return pairs.reshape(65536, 10)


_PAIR_TEXT = _pair_text()


def _decimal_list(values, last: bool) -> bytes:
    """ASCII of the bytes ``values`` as decimal numbers, each followed by ", " but the very last
    (``last``: this chunk ends the list): what ", ".join(map(str, values)) gives, without a
    Python string per byte."""
    even = len(values) - len(values) % 2
    rows = [_PAIR_TEXT[values[:even].view(">u2")], _BYTE_TEXT[values[even:]]]
    text = b"".join(row[row != 0].tobytes() for row in rows)
    return text[:-2] if last else text


def table_bin(table) -> bytes:
    """The box table as raw little-endian float32 RGBA texels of :func:`table_image`, row by row,
    preceded by nothing (width = min(boxes, TABLE_WIDTH), height from the size): what Unity's
    Texture2D.LoadRawTextureData (RGBAFloat) or a three.js DataTexture (RGBA, FloatType) take."""
    return table_image(table).astype("<f4").tobytes()

"""The binary FBX container (versions 7.x), read into a tree of nodes and written back, without
Blender: NumPy, zlib and struct only. It knows records, property types and the footer, nothing of
what the nodes mean (formats/fbx.py does the one patch the export needs).

The layout, as the public descriptions state it (Blender's "FBX binary file format
specification", 2013; the fbx-book and the fbxcel crate for the footer): a 27-byte header (``Kaydara FBX
Binary  \\0``, 0x1A 0x00, the version as uint32), the top-level records, a null record, and a
footer. A record: end offset (absolute), property count, property bytes (uint32 each below 7500,
uint64 from 7500), the name (uint8 length), the properties, then optionally a nested list of
records closed by a null record (13 zero bytes below 7500, 25 from 7500). A property: one type
code, then Y int16, C bool (one byte), I int32, F float32, D float64, L int64, S string and R raw
bytes (uint32 length), or an array f/d/l/i/b (uint32 count, encoding 0 raw or 1 zlib, stored
length) of float32, float64, int64, int32 or one-byte bools. The footer: a 16-byte id, zeros to
the next 16-byte boundary, 4 zeros, the version, 120 zeros and a fixed 16-byte magic.

Values read: Python bool, int, float and bytes, arrays as read-only NumPy arrays (little-endian
``<f4 <f8 <i8 <i4``, ``b`` as uint8 holding the stored bytes): to change one, put a new array in
its place. Written back with their type codes, so float64 stays float64; an array value must cast
safely to its code's dtype (float64 into ``f`` is refused). An array read from the file and still
in place is written back as the file stored it, compressed or not, without compressing it again;
a new array of more than 128 bytes is zlib-compressed (level 1), a smaller one written raw, as
Blender's FBX exporter does. zlib runs on a few threads at once (it releases the GIL). Any flaw
in a file (truncation, bad magic, an unknown type code, a length that disagrees) raises
ValueError naming it."""
from __future__ import annotations

import os
import struct
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from . import files

MAGIC = b"Kaydara FBX Binary  \x00\x1a\x00"
FOOTER_MAGIC = bytes.fromhex("f85a8c6adef5d97eece90ce3758f290b")
WIDE_VERSION = 7500  # from this version, record headers hold uint64 fields
COMPRESS_ABOVE = 128  # bytes of array data written raw; larger arrays are zlib-compressed
_MAX_DEPTH = 64  # files nest about 5 deep; a deeper one is refused well before Python's recursion limit
_SCALARS = {b"Y": "<h", b"C": "<?", b"I": "<i", b"F": "<f", b"D": "<d", b"L": "<q"}
_ARRAYS = {b"f": np.dtype("<f4"), b"d": np.dtype("<f8"), b"l": np.dtype("<i8"), b"i": np.dtype("<i4"),
           b"b": np.dtype("u1")}
_ARRAY_HEADER = struct.Struct("<III")  # count, encoding, stored length
# zlib's deflate emits at least 2 bits per 258-byte match: no stream inflates to more than 1032
# times its length, so an array declaring more cannot be what the file holds.
MAX_INFLATION = 1032
_INFLATE_PIECE = 1 << 20  # bytes inflated at a time into the array's own buffer


@dataclass
class Node:
    """One record: ``props`` and ``types`` (one type code per property, as bytes: b"SSD") side by
    side. ``null_record``: whether the record closes with a null record although it has no
    children (as read; None: only when it has no properties, the FBX SDK's rule). A record with
    children always closes with one."""
    name: bytes
    props: list = field(default_factory=list)
    types: bytes = b""
    children: list = field(default_factory=list)
    null_record: bool | None = None

    def child(self, name: bytes):
        """The first child named ``name``, or None."""
        return next((c for c in self.children if c.name == name), None)


@dataclass
class Document:
    """A whole file: the version, the top-level nodes and the footer's 16-byte id (kept as read:
    the FBX SDK ties it to the file's creation time). ``stored``: the arrays read, by id, with
    their type code, encoding and stored bytes, for writing them back unchanged."""
    version: int
    nodes: list
    footer_id: bytes
    stored: dict = field(default_factory=dict, repr=False, compare=False)


def read(path) -> Document:
    with open(path, "rb") as f:
        return decode(f.read())


def write(path, document: Document) -> None:
    """Write ``document`` to ``path`` once every byte of it is encoded, atomically
    (files.write_atomically: a failed write, a full disk or a file-size limit, leaves ``path`` as
    it was)."""
    data = encode(document)
    files.write_atomically(path, lambda temp: files.write_bytes(temp, data))


def decode(data: bytes) -> Document:
    if data[:len(MAGIC)] != MAGIC:
        if data.lstrip()[:1] in (b";", b"F"):
            raise ValueError("not a binary FBX file: it looks like an ASCII FBX (only binary FBX is read)")
        raise ValueError("not a binary FBX file: the header's magic 'Kaydara FBX Binary' is missing")
    if len(data) < len(MAGIC) + 4:
        raise ValueError("truncated FBX file: the header ends before its version")
    (version,) = struct.unpack_from("<I", data, len(MAGIC))
    if not 7000 <= version < 8000:
        raise ValueError(f"FBX version {version}: only binary FBX 7.x (7000 to 7999) is read")
    reader = _Reader(memoryview(data), version)
    nodes, pos = reader.records(len(MAGIC) + 4, len(data), 0, top=True)
    if len(data) - pos < 16:
        raise ValueError("truncated FBX file: the footer ends before its 16-byte id")
    places = [(props, k) for props in reader.with_arrays for k, v in enumerate(props) if isinstance(v, _StoredArray)]
    stored = {}
    for (props, k), values in zip(places, _in_threads(_StoredArray.values, [props[k] for props, k in places])):
        stored[id(values)] = (values, props[k].kind, props[k].encoding, props[k].raw)
        props[k] = values
    return Document(version, nodes, bytes(data[pos:pos + 16]), stored)


def _in_threads(function, items):
    """[function(item) ...], run on a few threads: zlib releases the GIL while it works."""
    if len(items) < 2:
        return [function(item) for item in items]
    with ThreadPoolExecutor(min(8, os.cpu_count() or 1)) as pool:
        return list(pool.map(function, items))


class _StoredArray:
    """An array as the file stores it, turned into values once the whole file has been read
    (the zlib ones several at once)."""

    def __init__(self, kind, encoding, raw, expected, where):
        self.kind, self.encoding, self.raw, self.expected, self.where = kind, encoding, raw, expected, where

    def values(self):
        if self.encoding == 0:
            return np.frombuffer(self.raw, _ARRAYS[self.kind])
        try:
            values = self.inflated()
        except zlib.error as error:
            raise ValueError(f"{self.where}: its zlib data is damaged ({error})") from None
        values.flags.writeable = False
        return values.view(_ARRAYS[self.kind])

    def inflated(self):
        """The zlib data inflated piece by piece into one buffer of the declared size (a single
        decompress call would hold its output twice at the end), refused before anything is
        allocated when the declared size is more than the stored bytes can inflate to."""
        if self.expected > MAX_INFLATION * len(self.raw):
            raise ValueError(f"{self.where} declares {self.expected} bytes from {len(self.raw)} zlib bytes: "
                             f"more than zlib inflates to (at most {MAX_INFLATION} times)")
        try:
            out = np.empty(self.expected, np.uint8)
        except MemoryError:
            raise ValueError(f"{self.where} needs {self.expected} bytes of memory, more than is free") from None
        inflate, tail, filled = zlib.decompressobj(), self.raw, 0
        while filled < self.expected:
            piece = inflate.decompress(tail, min(_INFLATE_PIECE, self.expected - filled))
            if not piece:
                break
            out[filled:filled + len(piece)] = np.frombuffer(piece, np.uint8)
            filled, tail = filled + len(piece), inflate.unconsumed_tail
        if filled == self.expected and not inflate.eof:
            extra = inflate.decompress(tail, 1)  # the stream's end, or data past the declared size
            filled, tail = filled + len(extra), inflate.unconsumed_tail
        if filled != self.expected or tail or not inflate.eof:
            raise ValueError(f"{self.where}: its zlib data does not inflate to {self.expected} bytes")
        return out


class _Reader:
    def __init__(self, data: memoryview, version: int):
        self.data = data
        self.mismatch = f": the file is damaged or its header's version {version} does not match its records"
        wide = version >= WIDE_VERSION
        self.header = struct.Struct("<QQQB" if wide else "<IIIB")
        self.null_length = self.header.size  # a null record: a header of zeros, name length 0 included
        self.with_arrays = []  # the property lists holding a _StoredArray

    def unpack(self, fmt, pos, end, what):
        size = struct.calcsize(fmt)
        if pos + size > end:
            raise ValueError(f"truncated FBX file: {what} at byte {pos} runs past byte {end}")
        return struct.unpack_from(fmt, self.data, pos)

    def take(self, pos, size, end, what):
        if pos + size > end:
            raise ValueError(f"truncated FBX file: {what} at byte {pos} ({size} bytes) runs past byte {end}")
        return self.data[pos:pos + size], pos + size

    def records(self, pos, end, depth, top=False):
        """The records from ``pos`` up to and including the null record that closes the list."""
        nodes = []
        while True:
            if pos + self.null_length > end:
                where = "the top-level records" if top else "a nested list"
                raise ValueError(f"truncated FBX file: {where} end at byte {end} without their null record")
            end_offset, count, props_length, name_length = self.header.unpack_from(self.data, pos)
            if end_offset == 0 and count == 0 and props_length == 0 and name_length == 0:
                return nodes, pos + self.null_length
            nodes.append(self.record(pos, end, depth, end_offset, count, props_length, name_length))
            pos = end_offset

    def record(self, pos, end, depth, end_offset, count, props_length, name_length):
        if depth >= _MAX_DEPTH:
            raise ValueError(f"FBX records nested more than {_MAX_DEPTH} deep at byte {pos}")
        if end_offset > len(self.data):
            raise ValueError(f"truncated FBX file: the record at byte {pos} ends at byte {end_offset}, past the "
                             f"file's end ({len(self.data)} bytes)")
        if not pos < end_offset <= end:
            raise ValueError(f"FBX record at byte {pos}: end offset {end_offset} lies outside its parent "
                             f"(bytes {pos} to {end}){self.mismatch}")
        name, cursor = self.take(pos + self.header.size, name_length, end_offset, "a record's name")
        name = bytes(name)
        if not _is_record_name(name):
            raise ValueError(f"FBX record at byte {pos}: its {len(name)}-byte name is not a record name (printable "
                             f"ASCII){self.mismatch}")
        props_end = cursor + props_length
        if props_end > end_offset:
            raise ValueError(f"FBX record '{_label(name)}' at byte {pos}: its {props_length} "
                             f"property bytes run past its end at byte {end_offset}")
        props, types = [], bytearray()
        for _ in range(count):
            kind, value, cursor = self.prop(cursor, props_end, name)
            props.append(value)
            types += kind
        if cursor != props_end:
            raise ValueError(f"FBX record '{_label(name)}' at byte {pos}: {count} properties "
                             f"fill {cursor - props_end + props_length} bytes, its header says {props_length}")
        if any(isinstance(value, _StoredArray) for value in props):
            self.with_arrays.append(props)
        node = Node(name, props, bytes(types))
        if cursor < end_offset:
            node.children, cursor = self.records(cursor, end_offset, depth + 1)
            node.null_record = True
            if cursor != end_offset:
                raise ValueError(f"FBX record '{_label(name)}' at byte {pos}: its nested list "
                                 f"ends at byte {cursor}, its header says {end_offset}")
        else:
            node.null_record = False
        return node

    def prop(self, pos, end, name):
        kind, pos = self.take(pos, 1, end, "a property's type code")
        kind = bytes(kind)
        if kind in _SCALARS:
            fmt = _SCALARS[kind]
            return kind, self.unpack(fmt, pos, end, f"a '{kind.decode()}' property")[0], pos + struct.calcsize(fmt)
        if kind in (b"S", b"R"):
            (length,) = self.unpack("<I", pos, end, f"a '{kind.decode()}' property's length")
            value, pos = self.take(pos + 4, length, end, f"a '{kind.decode()}' property")
            return kind, bytes(value), pos
        if kind in _ARRAYS:
            return kind, *self.array(kind, pos, end, name)
        label = repr(kind)[1:]
        raise ValueError(f"FBX record '{_label(name)}': unknown property type code {label} "
                         f"at byte {pos - 1}")

    def array(self, kind, pos, end, name):
        dtype = _ARRAYS[kind]
        count, encoding, stored = self.unpack(_ARRAY_HEADER.format, pos, end, f"a '{kind.decode()}' array header")
        raw, pos = self.take(pos + _ARRAY_HEADER.size, stored, end, f"a '{kind.decode()}' array")
        expected = count * dtype.itemsize
        where = f"FBX record '{_label(name)}': a '{kind.decode()}' array of {count} values"
        if encoding == 0 and stored != expected:
            raise ValueError(f"{where} stores {stored} bytes, not {expected}")
        if encoding not in (0, 1):
            raise ValueError(f"{where} has unknown encoding {encoding} (0 raw and 1 zlib are known)")
        return _StoredArray(kind, encoding, bytes(raw), expected, where), pos


def _is_record_name(name: bytes) -> bool:
    """Record names are identifiers (``Objects``, ``LayerElementUV``): printable ASCII."""
    return name.isascii() and name.decode().isprintable()


def _label(name: bytes) -> str:
    """A record name (checked by _is_record_name) for a message: its first 40 characters."""
    return name.decode() if len(name) <= 40 else name[:40].decode() + "..."


def encode(document: Document) -> bytes:
    """The file's bytes: the header with the document's version, its nodes, the null record and
    the footer."""
    if not 7000 <= document.version < 8000:
        raise ValueError(f"FBX version {document.version}: only binary FBX 7.x (7000 to 7999) is written")
    header = struct.Struct("<QQQB" if document.version >= WIDE_VERSION else "<IIIB")
    arrays = {}  # (id(node), property index) -> (encoding, stored bytes) of every array
    fresh = {}  # the arrays over COMPRESS_ABOVE bytes to compress (several at once)
    stack = list(document.nodes)
    while stack:
        node = stack.pop()
        stack += node.children
        for k, (kind, value) in enumerate(zip(node.types, node.props)):
            kind = bytes([kind])
            if kind not in _ARRAYS:
                continue
            kept = document.stored.get(id(value))
            if kept is not None and kept[0] is value and kept[1] == kind:
                arrays[id(node), k] = kept[2:]
            else:
                data = _array_bytes(kind, value, node.name.decode(errors="replace"))
                if len(data) > COMPRESS_ABOVE:
                    fresh[id(node), k] = data
                else:
                    arrays[id(node), k] = (0, data)
    arrays.update(zip(fresh, ((1, data) for data in _in_threads(_compress, list(fresh.values())))))
    chunks = [MAGIC, struct.pack("<I", document.version)]
    offset = len(MAGIC) + 4
    for node in document.nodes:
        offset = _encode_node(node, header, chunks, offset, arrays)
    chunks.append(bytes(header.size))
    offset += header.size
    if len(document.footer_id) != 16:
        raise ValueError(f"the FBX footer id must be 16 bytes, not {len(document.footer_id)}")
    offset += 16
    chunks += [document.footer_id, bytes(-offset % 16), bytes(4), struct.pack("<I", document.version), bytes(120),
               FOOTER_MAGIC]
    return b"".join(chunks)


def _compress(data):
    return zlib.compress(data, 1)


def _encode_node(node: Node, header: struct.Struct, chunks: list, offset: int, arrays: dict) -> int:
    """Append ``node``'s record at ``offset`` to ``chunks``; return the offset after it.
    ``arrays``: (encoding, stored bytes) of the arrays, by (id(node), property index)."""
    label = node.name.decode(errors="replace")
    if len(node.props) != len(node.types):
        raise ValueError(f"FBX node '{label}': {len(node.props)} properties, {len(node.types)} type codes")
    if len(node.name) > 255:
        raise ValueError(f"FBX node name '{label[:40]}...' is longer than 255 bytes")
    props = b"".join(_encode_prop(node.types[k:k + 1], value, label, arrays.get((id(node), k)))
                     for k, value in enumerate(node.props))
    at = len(chunks)
    chunks += [None, node.name, props]
    offset += header.size + len(node.name) + len(props)
    for child in node.children:
        offset = _encode_node(child, header, chunks, offset, arrays)
    if node.children or (node.null_record if node.null_record is not None else not node.props):
        chunks.append(bytes(header.size))
        offset += header.size
    if max(offset, len(props)) >> (64 if header.size > 13 else 32):
        raise ValueError(f"FBX node '{label}' ends at byte {offset}, past what this version's record headers hold")
    chunks[at] = header.pack(offset, len(node.props), len(props), len(node.name))
    return offset


def _encode_prop(kind: bytes, value, label: str, array) -> bytes:
    """One property's bytes; ``array``: an array's (encoding, stored bytes)."""
    try:
        if kind in _SCALARS:
            return kind + struct.pack(_SCALARS[kind], value)
        if kind in (b"S", b"R"):
            value = bytes(value)
            return kind + struct.pack("<I", len(value)) + value
    except (struct.error, TypeError) as error:
        raise ValueError(f"FBX node '{label}': {value!r} is no '{kind.decode()}' value ({error})") from None
    if kind not in _ARRAYS:
        raise ValueError(f"FBX node '{label}': unknown property type code {kind!r}")
    count, (encoding, data) = np.size(value), array
    if max(count, len(data)) >> 32:
        raise ValueError(f"FBX node '{label}': a '{kind.decode()}' array of {count} values is past what its "
                         f"uint32 header holds")
    return kind + _ARRAY_HEADER.pack(count, encoding, len(data)) + data


def _array_bytes(kind: bytes, value, label: str) -> bytes:
    """An array property's values as the file stores them (little-endian, uncompressed)."""
    dtype = _ARRAYS[kind]
    array = np.asarray(value) if isinstance(value, np.ndarray) else np.asarray(value, dtype)
    if not np.can_cast(array.dtype, dtype, "safe"):
        raise ValueError(f"FBX node '{label}': a {array.dtype} array does not fit a '{kind.decode()}' array "
                         f"({dtype}) without loss")
    return np.ascontiguousarray(array.reshape(-1), dtype).tobytes()

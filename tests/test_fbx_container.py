"""The binary FBX container codec (boxmarch.formats.fbx_container) against files Blender's own FBX
exporter wrote (the bpy module, and Debian's Blender 3.4 program): read and written back with no
change, each file reads with Blender's parser (io_scene_fbx.parse_fbx, which we did not write:
tests/fbx_reader.tree_differences) to the same records, type codes and values as the original,
arrays byte for byte. The comparison is shown to catch one changed value; replace_frame is shown
to change only the layer elements it patches. Hostile files (truncated, wrong magic, ASCII FBX,
an unknown type code, a zlib array whose count disagrees, flipped bytes) raise ValueError naming
the problem and leave replace_frame's target as it was."""
import json
import os
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

import boxmarch
from boxmarch.formats import fbx, fbx_container
from tests.engine_scene import skinned_scene
from tests.fbx_reader import read_fbx_geometry, tree_differences
from tests.helpers.blender_program import run_blender

# One scene for both Blenders: the factory cube (UVs, material), camera and light, plus an
# armature with two location keys (animation stacks, layers and curves).
SCENE_SCRIPT = """
import bpy
bpy.ops.object.armature_add(location=(2.0, 0.0, 0.0))
rig = bpy.context.object
rig.keyframe_insert("location", frame=1)
rig.location.x = 3.0
rig.keyframe_insert("location", frame=10)
bpy.ops.export_scene.fbx(filepath={path!r}, use_tspace=True, bake_anim=True)
"""


@pytest.fixture(scope="module")
def exports(bpy_module, tmp_path_factory):
    """{name: path} of FBX files the bpy module's exporter wrote: the scene above and the
    skinned rig (tangents, a skin, bind poses)."""
    bpy, folder = bpy_module, tmp_path_factory.mktemp("fbx_container")
    bpy.ops.wm.read_factory_settings(use_empty=False)
    out = {"scene": folder / "scene.fbx", "skinned": folder / "skinned.fbx"}
    exec(SCENE_SCRIPT.format(path=str(out["scene"])), {})
    bpy.ops.wm.read_factory_settings(use_empty=True)
    skinned_scene(bpy)
    bpy.ops.export_scene.fbx(filepath=str(out["skinned"]), use_tspace=True, bake_anim=False)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return out


def round_trip(source, target, version=None, fresh_arrays=False):
    """``source`` read and written to ``target`` (as ``version``; with ``fresh_arrays`` every array
    replaced by a copy, so that the writer encodes and compresses each itself)."""
    document = fbx_container.read(source)
    if version is not None:
        document.version = version
    stack = list(document.nodes)
    while fresh_arrays and stack:
        node = stack.pop()
        stack += node.children
        node.props = [np.array(v) if isinstance(v, np.ndarray) else v for v in node.props]
    fbx_container.write(target, document)
    return target.read_bytes()


def check_footer(data, version):
    """The footer as the format states it: the id, zeros to a 16-byte boundary, 4 zeros, the
    version, 120 zeros, the closing magic; the whole file a multiple of 16 bytes."""
    assert len(data) % 16 == 0
    assert data[-16:] == fbx_container.FOOTER_MAGIC and data[-136:-16] == bytes(120)
    assert struct.unpack("<I", data[-140:-136])[0] == version and data[-144:-140] == bytes(4)


def check_round_trip(source, target):
    """``source`` read and written to ``target`` reads the same in Blender's parser, with the
    format's footer, whether the arrays are written back as stored or encoded afresh; records
    and arrays come out byte for byte as Blender's exporter wrote them (its arrays over 128 bytes
    zlib level 1, as here): only the footer's padding differs."""
    original = source.read_bytes()
    document = fbx_container.read(source)
    id_end = original.rindex(document.footer_id) + 16
    for fresh_arrays in (False, True):
        data = round_trip(source, target, fresh_arrays=fresh_arrays)
        assert tree_differences(source, target) == [], fresh_arrays
        check_footer(data, document.version)
        assert data[:id_end] == original[:id_end], fresh_arrays


def test_round_trip_reads_the_same_in_blenders_parser(exports, tmp_path):
    for name, source in exports.items():
        check_round_trip(source, tmp_path / f"{name}.fbx")


def test_version_7500_records_read_the_same(exports, tmp_path):
    """From 7500 record headers are 64-bit: the same tree written as 7500 reads the same in
    Blender's parser (version aside)."""
    target = tmp_path / "wide.fbx"
    data = round_trip(exports["skinned"], target, version=7500)
    check_footer(data, 7500)
    assert fbx_container.read(target).version == 7500
    assert tree_differences(exports["skinned"], target) == ["version 7400 != 7500"]
    assert len(data) > exports["skinned"].stat().st_size  # wider headers


def test_comparison_catches_one_changed_value(exports, tmp_path):
    """Negative control: one control point moved by one float64 ulp, and one float64 property
    written as float32, are each reported by the comparison."""
    document = fbx_container.read(exports["skinned"])
    objects = next(n for n in document.nodes if n.name == b"Objects")
    vertices = objects.child(b"Geometry").child(b"Vertices")
    assert vertices.types == b"d" and vertices.props[0].dtype == np.float64
    with pytest.raises(ValueError, match="read-only"):  # an array read is changed by replacing it
        vertices.props[0][4] = 0.0
    moved = vertices.props[0].copy()
    moved[4] = np.nextafter(moved[4], np.inf)
    vertices.props[0] = moved
    fbx_container.write(tmp_path / "moved.fbx", document)
    found = tree_differences(exports["skinned"], tmp_path / "moved.fbx")
    assert len(found) == 1 and "/Objects/Geometry/Vertices property 0" in found[0], found

    document = fbx_container.read(exports["skinned"])
    settings = next(n for n in document.nodes if n.name == b"GlobalSettings").child(b"Properties70")
    scale = next(p for p in settings.children if p.props[0] == b"UnitScaleFactor")
    scale.types = scale.types[:-1] + b"F"
    fbx_container.write(tmp_path / "narrowed.fbx", document)
    found = tree_differences(exports["skinned"], tmp_path / "narrowed.fbx")
    assert len(found) == 1 and "/GlobalSettings/Properties70/P" in found[0], found


def test_replace_frame_changes_only_the_frame_layers(exports, tmp_path):
    """The patched file: the normal, tangent and binormal layers hold the given vectors (as
    tests/fbx_reader.py reads them), and every other record reads as the exporter wrote it."""
    target = tmp_path / "patched.fbx"
    target.write_bytes(exports["scene"].read_bytes())
    corners = len(read_fbx_geometry(exports["scene"])["vertex"])
    frames = {channel: np.random.default_rng(k).normal(size=(corners, 3))
              for k, channel in enumerate(("NORMAL", "TANGENT", "BINORMAL"))}
    fbx.replace_frame(str(target), {"Cube": frames})
    raw = read_fbx_geometry(target)
    for channel in frames:
        assert np.array_equal(raw[channel.lower()], frames[channel])
    found = tree_differences(exports["scene"], target, limit=1000)
    assert found and all(any(f"/Geometry/{layer}/" in line for layer in (
        "LayerElementNormal", "LayerElementTangent", "LayerElementBinormal")) for line in found), found


@pytest.mark.slow  # a Blender 3.4 program run
@pytest.mark.blender_program
def test_round_trip_of_blender_34_export(bpy_module, tmp_path):
    """The same scene exported by Debian's Blender 3.4 program (its older FBX writer, which closes
    more records with a null record)."""
    source = tmp_path / "scene34.fbx"
    run_blender(["--background", "--factory-startup", "--python-exit-code", "1",
                 "--python-expr", SCENE_SCRIPT.format(path=str(source))], tmp_path)
    document = fbx_container.read(source)
    creator = next(n for n in document.nodes if n.name == b"Creator").props[0]
    assert b" - 3.4." in creator, creator
    check_round_trip(source, tmp_path / "written.fbx")


# Hostile files: a small document written here, then damaged at known bytes.

def small_document():
    return fbx_container.Document(7400, [
        fbx_container.Node(b"Header", [123456789, b"text", 1.5, True], b"ISDC"),
        fbx_container.Node(b"Data", [np.arange(100, dtype=np.float64)], b"d",
                           [fbx_container.Node(b"Empty")]),
    ], bytes(range(16)))


def nested(depth):
    node = fbx_container.Node(b"Leaf", [1], b"I")
    for _ in range(depth):
        node = fbx_container.Node(b"Box", [], b"", [node])
    return node


def damaged(data, old, new):
    assert data.count(old) == 1
    return data.replace(old, new)


def with_header_extension():
    """small_document behind a header record like the exporter's (children, a long string)."""
    document = small_document()
    creator = fbx_container.Node(b"Creator", [b"Blender (stable FBX IO) - 3.4.1" + bytes(200)], b"S")
    document.nodes.insert(0, fbx_container.Node(b"FBXHeaderExtension", [], b"", [
        fbx_container.Node(b"FBXHeaderVersion", [1003], b"I"), creator]))
    return fbx_container.encode(document)


def one_array_file(count, encoding, stored, version=7400):
    """A file whose one record holds a 'd' array of ``count`` values stored as ``stored`` bytes."""
    array = b"d" + struct.pack("<III", count, encoding, len(stored)) + stored
    header = struct.Struct("<IIIB")
    record = header.pack(27 + header.size + 4 + len(array), 1, len(array), 4) + b"Data" + array
    body = fbx_container.MAGIC + struct.pack("<I", version) + record + bytes(header.size)
    return (body + bytes(16) + bytes(-(len(body) + 16) % 16) + bytes(4) + struct.pack("<I", version) + bytes(120)
            + fbx_container.FOOTER_MAGIC)


def zeros_stream(mib):
    """A zlib stream of ``mib`` MiB of zero bytes (about 1030:1), made a MiB at a time."""
    deflate, zeros = zlib.compressobj(9), bytes(1 << 20)
    return b"".join(deflate.compress(zeros) for _ in range(mib)) + deflate.flush()


def hostile_files():
    """{what: (bytes, words the ValueError must hold)}."""
    good = fbx_container.encode(small_document())
    header_extension = with_header_extension()
    long_name = fbx_container.encode(fbx_container.Document(7400, [fbx_container.Node(b"A" * 200, [7], b"I")], bytes(16)))
    wide = fbx_container.encode(fbx_container.Document(7500, fbx_container.decode(header_extension).nodes, bytes(16)))
    compressed = zlib.compress(np.arange(100, dtype=np.float64).tobytes(), 1)
    array_header = struct.pack("<III", 100, 1, len(compressed))
    return {
        "truncated": (good[:len(good) // 2], "truncated"),
        "truncated header": (good[:25], "truncated"),
        "empty": (b"", "magic"),
        "wrong magic": (b"Kaydara FBX Binary  \x00\x1b\x00" + good[23:], "magic"),
        "ascii": (b"; FBX 7.4.0 project file\nFBXHeaderExtension:  {\n}\n", "ASCII"),
        "version 6100": (good[:23] + struct.pack("<I", 6100) + good[27:], "version 6100"),
        "unknown type code": (damaged(good, b"I" + struct.pack("<i", 123456789), b"Q" + struct.pack("<i", 123456789)),
                              "unknown property type code 'Q'"),
        "zlib count too small": (damaged(good, array_header, struct.pack("<III", 99, 1, len(compressed))),
                                 "does not inflate to 792 bytes"),
        "zlib count too large": (damaged(good, array_header, struct.pack("<III", 101, 1, len(compressed))),
                                 "does not inflate to 808 bytes"),
        "zlib count zero": (damaged(good, array_header, struct.pack("<III", 0, 1, len(compressed))),
                            "does not inflate to 0 bytes"),
        "nested 70 deep": (fbx_container.encode(fbx_container.Document(7400, [nested(70)], bytes(16))),
                           "nested more than 64 deep"),
        "zlib damaged": (damaged(good, compressed, compressed[:10] + b"\xff" * 8 + compressed[18:]), "zlib"),
        "unknown encoding": (damaged(good, array_header, struct.pack("<III", 100, 7, len(compressed))),
                             "unknown encoding 7"),
        "no footer": (good[:-160], "footer"),
        "7500 header over 7.4 records": (header_extension[:23] + struct.pack("<I", 7500) + header_extension[27:],
                                         "version 7500 does not match its records"),
        "7400 header over 7.5 records": (wide[:23] + struct.pack("<I", 7400) + wide[27:],
                                         "version 7400 does not match"),
        "binary record name": (damaged(good, b"Empty", b"Em\x00\xffy"), "not a record name"),
        "unknown type code in a record named by 200 characters": (damaged(long_name, b"I" + struct.pack("<i", 7),
                                                                          b"Q" + struct.pack("<i", 7)),
                                                                  "'A{40}...': unknown property type code 'Q'"),
        # 8 GiB declared from about 1 KiB of zlib data: refused before anything is allocated
        "zlib count past 1032:1": (one_array_file(1 << 30, 1, zlib.compress(bytes(1 << 20), 9)),
                                   "more than zlib inflates to"),
    }


def test_hostile_file_messages_are_one_short_printable_line():
    """No message quotes the file's binary: a misread record name is described, not printed."""
    for what, (data, _words) in hostile_files().items():
        with pytest.raises(ValueError) as caught:
            fbx_container.decode(data)
        message = str(caught.value)
        assert message.isprintable() and len(message) < 240, (what, message)


def geometry_file(name, code):
    objects = fbx_container.Node(b"Objects", [], b"", [fbx_container.Node(b"Geometry", [1, name, b"Mesh"],
                                                                          b"I" + code + b"S")])
    return fbx_container.encode(fbx_container.Document(7400, [objects], bytes(16)))


@pytest.mark.parametrize("name, code, words", [(7, b"L", "'L' property, not a string"),
                                               (b"\xff\xfeCube\x00\x01Geometry", b"S", "not UTF-8 text"),
                                               (2.5, b"D", "'D' property, not a string")])
def test_replace_frame_refuses_a_geometry_name_that_is_no_text(name, code, words, tmp_path):
    target = tmp_path / "target.fbx"
    target.write_bytes(geometry_file(name, code))
    with pytest.raises(ValueError, match=words):
        fbx.replace_frame(str(target), {"Cube": {}})
    assert target.read_bytes() == geometry_file(name, code)


def read_in_child(path, limit_kb=None):
    """fbx_memory_child's JSON for ``path``, optionally under an address-space limit (ulimit -v)."""
    env = dict(os.environ, PYTHONPATH=str(Path(boxmarch.__file__).parent.parent), OPENBLAS_NUM_THREADS="1")
    child = f"{sys.executable} {Path(__file__).parent / 'hostile' / 'fbx_memory_child.py'} {path}"
    command = f"ulimit -v {limit_kb}; exec {child}" if limit_kb else f"exec {child}"
    run = subprocess.run(["bash", "-c", command], env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, (run.returncode, run.stdout, run.stderr[-2000:])
    return json.loads(run.stdout)


@pytest.mark.slow
def test_a_zlib_array_inflates_into_its_own_buffer_only(tmp_path):
    """A 64 KiB file whose array inflates to 64 MiB (within zlib's 1032:1) is read holding the
    values about once (a single decompress call held them twice: 128 MiB)."""
    path = tmp_path / "zeros.fbx"
    path.write_bytes(one_array_file(8 << 20, 1, zeros_stream(64)))
    result = read_in_child(path)
    assert result["outcome"] == "read"
    assert result["peak_bytes"] < 1.25 * (64 << 20), result


@pytest.mark.slow
def test_a_zlib_bomb_is_refused_before_its_memory_is_reserved(tmp_path):
    """8 GiB declared from about 1 KiB of zlib data (hostile_files' "zlib count past 1032:1"):
    refused, and the read reserves less than an eighth of it in address space (threads' stacks
    and arenas included). Without the check the 8 GiB are reserved (untouched pages, so the
    resident peak alone would not see it) and the read fails later on the stream's length."""
    path = tmp_path / "bomb.fbx"
    data, words = hostile_files()["zlib count past 1032:1"]
    path.write_bytes(data)
    result = read_in_child(path)
    assert result["peak_address_bytes"] < (8 << 30) / 8, result
    assert result["outcome"].startswith("ValueError") and words in result["outcome"], result


@pytest.mark.slow
def test_an_array_past_the_free_memory_raises_value_error(tmp_path):
    """1 GiB declared (a 1 MiB zero stream) under an 800 MB address-space limit: ValueError, not MemoryError."""
    path = tmp_path / "large.fbx"
    path.write_bytes(one_array_file(1 << 27, 1, zeros_stream(1024)))
    result = read_in_child(path, limit_kb=800_000)
    assert result["outcome"].startswith("ValueError") and "bytes of memory" in result["outcome"], result


def test_small_document_round_trips():
    data = fbx_container.encode(small_document())
    check_footer(data, 7400)
    document = fbx_container.decode(data)
    header, values = document.nodes
    assert header.props == [123456789, b"text", 1.5, True] and header.types == b"ISDC"
    assert values.types == b"d" and values.props[0].dtype == np.float64
    assert np.array_equal(values.props[0], np.arange(100))
    assert values.children[0].name == b"Empty" and document.footer_id == bytes(range(16))
    assert fbx_container.encode(document) == data


@pytest.mark.parametrize("what", list(hostile_files()))
def test_hostile_file_raises_value_error_and_replace_frame_changes_nothing(what, tmp_path):
    data, words = hostile_files()[what]
    with pytest.raises(ValueError, match=words):
        fbx_container.decode(data)
    target = tmp_path / "target.fbx"
    target.write_bytes(data)
    with pytest.raises(ValueError, match=words):
        fbx.replace_frame(str(target), {"Cube": {}})
    assert target.read_bytes() == data


def test_lossy_writes_are_refused():
    for node in (fbx_container.Node(b"N", [np.zeros(3)], b"f"),  # float64 into float32
                 fbx_container.Node(b"N", [np.zeros(3, np.int64)], b"i"),
                 fbx_container.Node(b"N", [2 ** 31], b"I"),
                 fbx_container.Node(b"N", [1.0], b"SD")):
        with pytest.raises(ValueError):
            fbx_container.encode(fbx_container.Document(7400, [node], bytes(16)))


@pytest.mark.slow  # 460 decodes: about 5 s of CPU
def test_flipped_bytes_never_crash(exports):
    """Every single-byte change at 400 seeded places either reads or raises ValueError."""
    original = exports["scene"].read_bytes()
    rng = np.random.default_rng(7)
    failures = 0
    for at, value in zip(rng.integers(0, len(original), 400), rng.integers(0, 256, 400)):
        data = bytearray(original)
        data[at] = value
        try:
            fbx_container.decode(bytes(data))
        except ValueError:
            failures += 1
    assert failures > 0
    for cut in np.linspace(0, len(original) - 180, 60).astype(int):
        with pytest.raises(ValueError):
            fbx_container.decode(original[:cut])

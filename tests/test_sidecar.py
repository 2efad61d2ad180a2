"""The sidecar NAME.boxmarch.json of every preset and layout: valid against the shipped JSON
Schema, and true of the file it describes. The file is read with the tests' own readers (glTF,
FBX) or Blender's library loader (.blend); the channels named by the sidecar are decoded with the
sidecar's encodings and axes, written out here from docs/FORMAT.md, and must give exactly
``box_count`` box origins (for indexed layouts: one index per origin, 0 .. box_count - 1) with
every vertex inside its box's half-extents. A sidecar naming a wrong channel fails these checks
(the negative controls below swap two channels)."""
import copy
import json

import numpy as np
import pytest

from tests.engine_scene import baked_scene, rotate, skinned_scene, table_texels
from tests.helpers.sidecar_files import file_channels, values

jsonschema = pytest.importorskip("jsonschema")

EXPORTS = [("GLTF", "NORMAL_FRAME"), ("GLTF", "UV_FRAME"), ("GLTF", "CLASSIC"), ("GODOT3", "NORMAL_COLOR"),
           ("UNITY", "UV_FRAME"), ("UNITY", "CLASSIC"), ("UNITY", "NORMAL_FRAME"), ("UNREAL", "UV_FRAME"),
           ("BLENDER", "CLASSIC")]


def schema():
    from boxmarch.formats import sidecar

    with open(sidecar.SCHEMA_PATH) as f:
        return json.load(f)


def test_the_schema_lists_every_preset():
    """The schema's preset enum names exactly the presets (a preset missing there would write
    sidecars its own schema refuses)."""
    from boxmarch.formats import presets

    assert set(schema()["properties"]["preset"]["enum"]) == set(presets.PRESETS)


def decode(positions, channels, sidecar, table=None):
    """(origins, offsets f, half-extents or None, index or None) per vertex, in the data frame."""
    axes, q = sidecar["axes"], sidecar["quantities"]
    to_data = np.array(axes["data_from_file"])
    turn = to_data / axes["length_scale"]
    p = positions @ to_data.T
    offset = q["offset"]
    if offset["encoding"] == "classic_colour":
        c = values(channels, offset["channels"])
        f = (c[:, :3] * 2.0 - 1.0) / c[:, 3:]
    else:
        f = values(channels, offset["channels"])
    frame = q["frame"]
    if frame["encoding"] == "quaternion_xyzw":
        origins = p + rotate(f, values(channels, frame["channels"]))
    else:
        z, x = channels["NORMAL"][:, :3] @ turn.T, channels["TANGENT"][:, :3] @ turn.T
        y = channels["BINORMAL"] @ turn.T if "BINORMAL" in channels else np.cross(z, x) * channels["TANGENT"][:, 3:]
        origins = p + x * f[:, :1] + y * f[:, 1:2] + z * f[:, 2:]
    index = values(channels, q["index"]["channels"])[:, 0] if "index" in q else None
    half = None
    if "half_extents" in q:
        spec = q["half_extents"]
        half = table[index.astype(int), :3] if spec["encoding"] == "box_table" else values(channels, spec["channels"])
    return origins, f, half, index


def clusters(points, tolerance):
    """Cluster number of each point: points within ``tolerance`` of a cluster's first point."""
    firsts, out = [], np.empty(len(points), int)
    for i, point in enumerate(points):
        near = [k for k, first in enumerate(firsts) if np.linalg.norm(point - first) <= tolerance]
        if not near:
            firsts.append(point)
        out[i] = near[0] if near else len(firsts) - 1
    return out


def check_against_file(bpy, path, sidecar):
    """Every claim the sidecar makes about ``path`` that the file can show; AssertionError if not."""
    positions, channels = file_channels(bpy, path, sidecar)
    table = None
    if sidecar["quantities"].get("half_extents", {}).get("encoding") == "box_table":
        table = table_texels((path.parent / sidecar["quantities"]["half_extents"]["file"]).read_text())
    origins, f, half, index = decode(positions, channels, sidecar, table)
    boxes = sidecar["box_count"]
    box = clusters(origins, 1e-4 * sidecar["axes"]["length_scale"])
    assert box.max() + 1 == boxes, (box.max() + 1, boxes)
    assert sum(m["boxes"] for m in sidecar["meshes"]) == boxes
    if index is not None:
        assert np.array_equal(index, np.rint(index)) and sorted(set(index.astype(int))) == list(range(boxes))
        assert len(set(zip(box, index.astype(int)))) == boxes  # one index per origin
    if half is not None:  # each vertex lies inside its box: |f| <= h per local axis
        assert np.all(np.abs(f) <= half * (1 + 1e-5) + 1e-7), float((np.abs(f) - half).max())


@pytest.mark.parametrize("preset, layout", EXPORTS)
def test_every_sidecar_validates_and_describes_its_file(blender, tmp_path, preset, layout):
    from boxmarch.export import scene
    from boxmarch.formats import sidecar, presets

    ob, centres, _sizes, _rotations = baked_scene(blender)
    path = tmp_path / f"boxes{presets.PRESETS[preset].extension}"
    report = scene.export_objects(blender.context, [ob], preset, str(path), layout)
    written = json.loads((tmp_path / "boxes.boxmarch.json").read_text())
    assert report["sidecar"] == str(tmp_path / "boxes.boxmarch.json")
    jsonschema.validate(written, schema())
    assert (written["format_version"], written["preset"], written["layout"], written["skinned"]) == (1, preset, layout,
                                                                                                      False)
    assert written["box_count"] == len(centres) and written["file"] == path.name
    assert written["decode_error"]["export"] == report["transform_error"] < 1e-6
    assert written["decode_error"]["default_import"] == report["default_import_error"]
    table = {"GODOT3": ["boxes.boxes.tres", "boxes.glb.import"], "BLENDER": []}.get(
        preset, [] if layout == "CLASSIC" else ["boxes.boxes.bin"])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([path.name, "boxes.boxmarch.json"] + table)
    assert (written["box_table"] or {}).get("file") == (table[0] if table else None)
    check_against_file(blender, path, written)
    assert sorted(sidecar.written_beside(str(path), preset, layout)) == sorted(str(p) for p in tmp_path.iterdir()
                                                                               if p != path)


@pytest.mark.parametrize("preset, wrong", [
    ("UNITY", lambda s: s["file_channels"].update(UV3=s["file_channels"]["UV5"])),      # offset read from the half-extents
    ("GLTF", lambda s: s["axes"].update(data_from_file=np.diag([-1.0, 1.0, 1.0]).tolist())),  # a mirror the file lacks
    ("UNREAL", lambda s: s["axes"].update(v_flipped_in_file=False)),                     # v read as the file holds it
])
def test_a_sidecar_that_misnames_the_file_fails_the_check(blender, tmp_path, preset, wrong):
    """Negative controls of check_against_file: each sidecar edited in one claim must fail."""
    from boxmarch.export import scene
    from boxmarch.formats import presets

    ob, *_ = baked_scene(blender)
    path = tmp_path / f"boxes{presets.PRESETS[preset].extension}"
    scene.export_objects(blender.context, [ob], preset, str(path))
    written = json.loads((tmp_path / "boxes.boxmarch.json").read_text())
    check_against_file(blender, path, written)
    edited = copy.deepcopy(written)
    wrong(edited)
    with pytest.raises(AssertionError):
        check_against_file(blender, path, edited)


@pytest.mark.parametrize("preset", ["GLTF", "UNITY"])
def test_skinned_sidecar_says_so_and_describes_the_rest_pose_file(blender, tmp_path, preset):
    from boxmarch.export import scene
    from boxmarch.formats import presets

    ob, rig = skinned_scene(blender)
    path = tmp_path / f"skinned{presets.PRESETS[preset].extension}"
    report = scene.export_objects(blender.context, [ob], preset, str(path))
    written = json.loads((tmp_path / "skinned.boxmarch.json").read_text())
    jsonschema.validate(written, schema())
    assert written["skinned"] is True and written["layout"] == report["layout"] == "NORMAL_FRAME"
    assert written["skins"] == {ob.name: {"armature": rig.name, "bones": ["bone0", "bone1", "bone2"]}}
    check_against_file(blender, path, written)


def test_schema_refuses_a_sidecar_without_an_agreed_key_or_with_a_wrong_type(blender, tmp_path):
    from boxmarch.export import scene

    ob, *_ = baked_scene(blender)
    scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "boxes.glb"))
    written = json.loads((tmp_path / "boxes.boxmarch.json").read_text())
    for key, bad in (("format_version", "1"), ("box_count", 9.5), ("skinned", 0), ("layout", "OTHER")):
        edited = dict(written, **{key: bad})
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(edited, schema())
        del edited[key]
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(edited, schema())

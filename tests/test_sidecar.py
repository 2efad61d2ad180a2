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

from tests.engine_scene import baked_scene, box_corners, rotate, skinned_scene, table_texels
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb
from tests.helpers.sidecar_files import file_channels, values
from tests.helpers.tools import need


@pytest.fixture(scope="module")
def jsonschema():
    try:
        import jsonschema
    except ImportError:
        jsonschema = None
    need(None if jsonschema else "jsonschema is not installed (pip install jsonschema)")
    return jsonschema

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


# Metres per unit of the frame each engine holds the box data in after its importer, from the
# engines' documentation: glTF and three.js, Godot, Unity (Convert Units: 1 unit per metre),
# Blender in metres; Unreal in centimetres.
DATA_UNIT_METRES = {"GLTF": 1.0, "GODOT3": 1.0, "UNITY": 1.0, "UNREAL": 0.01, "BLENDER": 1.0}


def file_vertices_and_unit(bpy, path):
    """([Blender vertices per mesh of the file], metres per file unit), read from the file: a
    .glb's distinct positions per glTF mesh (the exporter splits vertices by corner, never joins
    them) in metres (glTF 2.0, 3.4); an FBX geometry's control points in the unit its
    GlobalSettings UnitScaleFactor gives (centimetres per unit); a .blend's mesh vertices in its
    scene's unit scale (a .blend of meshes alone: Blender units, metres)."""
    if path.suffix == ".glb":
        counts = [len(np.unique(np.concatenate([p["POSITION"] for p in mesh["primitives"]]), axis=0))
                  for mesh in read_glb(path)]
        return counts, 1.0
    if path.suffix == ".fbx":
        raw = read_fbx_geometry(path)
        return [len(raw["control_points"])], float(raw["settings"]["UnitScaleFactor"]) / 100.0
    with bpy.data.libraries.load(str(path)) as (src, dst):
        dst.meshes, dst.scenes = list(src.meshes), list(src.scenes)
    unit = dst.scenes[0].unit_settings.scale_length if dst.scenes else 1.0  # no scene: Blender units, metres
    return [len(mesh.vertices) for mesh in dst.meshes], float(unit)


def reach(points):
    """The largest distance between two of ``points`` (any rotation or reflection keeps it)."""
    points = np.unique(np.asarray(points, np.float64), axis=0)
    return float(max(np.linalg.norm(points - p, axis=1).max() for p in points))


def check_counts_and_units(bpy, path, sidecar):
    """vertex_count, meshes[].vertices and axes.length_scale against the file read independently:
    its vertex counts, and (metres per file unit) / (metres per unit of the engine's data frame)."""
    counts, file_unit_metres = file_vertices_and_unit(bpy, path)
    assert sorted(m["vertices"] for m in sidecar["meshes"]) == sorted(counts), (sidecar["meshes"], counts)
    assert sidecar["vertex_count"] == sum(counts), (sidecar["vertex_count"], counts)
    expected_scale = file_unit_metres / DATA_UNIT_METRES[sidecar["preset"]]
    assert abs(sidecar["axes"]["length_scale"] - expected_scale) <= 1e-12 * expected_scale, (
        sidecar["axes"]["length_scale"], expected_scale)


def check_against_file(bpy, path, sidecar):
    """Every claim the sidecar makes about ``path`` that the file can show; AssertionError if not."""
    check_counts_and_units(bpy, path, sidecar)
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
def test_every_sidecar_validates_and_describes_its_file(blender, jsonschema, tmp_path, preset, layout):
    from boxmarch.export import scene
    from boxmarch.formats import sidecar, presets

    ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path / f"boxes{presets.PRESETS[preset].extension}"
    report = scene.export_objects(blender.context, [ob], preset, str(path), layout)
    written = json.loads((tmp_path / "boxes.boxmarch.json").read_text())
    assert report["sidecar"] == str(tmp_path / "boxes.boxmarch.json")
    # the file's unit read from the file is its coordinates' unit: the scene's reach in metres
    positions, _channels = file_channels(blender, path, written)
    counts, file_unit_metres = file_vertices_and_unit(blender, path)
    corners = np.concatenate([box_corners(*box) for box in zip(centres, sizes, rotations)])
    assert sum(counts) == len(corners)
    assert abs(reach(positions) * file_unit_metres / reach(corners) - 1.0) < 1e-6
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
def test_skinned_sidecar_says_so_and_describes_the_rest_pose_file(blender, jsonschema, tmp_path, preset):
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


def test_schema_refuses_a_sidecar_without_an_agreed_key_or_with_a_wrong_type(blender, jsonschema, tmp_path):
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

"""Every engine preset's default layout, for boxes of 0.01-1000 units up to 1000 units from the
object origin: what the file holds (read without Blender: tests/gltf_reader.py, Blender's FBX
parser) decodes with docs/ENGINES.md's formulas, in float64, to each box's bounds centre and
half-extents within 1e-5 of the half-extent. The reference is the box as the file stores it (its
float32 corners, projected on the decoded axes): at 1000 units float32 itself moves a corner by
6e-5, more than 1e-5 of a 0.01 box, and the bake is exact relative to what is stored (as
test_core's far-box test states for the bake). GLTF and GODOT3 export two objects: glTF
numbers each mesh's boxes from 0, GODOT3 continues the numbers so one box table holds both."""
import numpy as np
import pytest

from boxmarch import mesh_io, scenes
from tests.engine_scene import UNITY, UNREAL, decode_normal_frame, decode_uv_frame, imported, table_texels
from tests.fbx_reader import read_fbx_geometry
from tests.gltf_reader import read_glb

BOUND = 1e-5


def far_boxes(seed, n):
    """(centres, sizes, rotations): largest sizes log-uniform in 0.01..1000, up to 1000 units out."""
    rng = np.random.default_rng(seed)
    largest = np.exp(rng.uniform(np.log(0.01), np.log(1000.0), n))
    sizes = largest[:, None] * rng.uniform(0.3, 1.0, (n, 3))
    sizes[np.arange(n), rng.integers(0, 3, n)] = largest
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    centres = directions * rng.uniform(0.0, 1000.0, (n, 1))
    centres[:4] = directions[:4] * 1000.0
    return centres, sizes, scenes.random_rotations(n, rng)


def baked_objects(bpy, count):
    objects = []
    for k in range(count):
        centres, sizes, rotations = far_boxes(40 + k, 60)
        arrays = scenes.box_arrays(centres, sizes, rotations)
        mesh = mesh_io.new_mesh(f"Far{k}", arrays[0], arrays[2], arrays[3], arrays[4], edges=arrays[1])
        ob = bpy.data.objects.new(f"Far{k}", mesh)
        bpy.context.scene.collection.objects.link(ob)
        objects.append(ob)
    for ob in bpy.context.scene.objects:
        ob.select_set(ob in objects)
    bpy.context.view_layer.objects.active = objects[0]
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    return objects


def check_boxes(positions, origins, axes, half, index):
    """Groups vertices by the decoded box number; each group must be one box: 8 corners, the
    decoded origin its bounds centre in the decoded frame, h its bounds half-size. Returns the
    worst origin and half-extent errors over the largest half-extent."""
    assert np.array_equal(index, np.rint(index))
    worst = [0.0, 0.0]
    for b in np.unique(index):
        v = index == b
        corners = np.unique(positions[v], axis=0)
        assert len(corners) == 8, (b, len(corners))
        frame = axes[v][0]  # columns x, y, z
        assert np.abs(axes[v] - frame).max() < 1e-6  # one frame per box
        local = (corners - corners[0]) @ frame  # from a corner: a lever of 1000 units would
        centre = corners[0] + frame @ ((local.min(0) + local.max(0)) / 2)  # amplify the frame's rounding
        own_half = (local.max(0) - local.min(0)) / 2
        reach = own_half.max()
        worst[0] = max(worst[0], np.linalg.norm(origins[v] - centre, axis=1).max() / reach)
        worst[1] = max(worst[1], np.abs(half[v] - own_half).max() / reach)
    return worst


@pytest.mark.parametrize("layout", ["NORMAL_FRAME", "UV_FRAME"])
def test_gltf_decodes_far_and_tiny_boxes(blender, tmp_path, layout):
    baked_objects(blender, 2)
    path = tmp_path / "far.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF", layout=layout) == {"FINISHED"}
    numbers = []
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        pos = p["POSITION"].astype(np.float64)
        uv = [p[f"TEXCOORD_{n}"].astype(np.float64) for n in range(1, 7 if layout == "UV_FRAME" else 5)]
        if layout == "NORMAL_FRAME":
            offset = np.concatenate([uv[0], uv[1][:, :1]], 1)
            origins, axes, half = decode_normal_frame(pos, p["NORMAL"].astype(np.float64),
                                                      p["TANGENT"].astype(np.float64), offset,
                                                      np.concatenate([uv[2], uv[3][:, :1]], 1))
            index = uv[1][:, 1]
        else:
            origins, axes, half, index = decode_uv_frame(pos, uv)
        errors = check_boxes(pos, origins, axes, half, index)
        assert errors[0] < BOUND and errors[1] < BOUND, errors
        numbers.append(np.unique(index))
    for k, mesh_numbers in enumerate(numbers):  # numbers run on across meshes: one box table row each
        assert np.array_equal(mesh_numbers, 60 * k + np.arange(60))


def test_godot3_decodes_far_and_tiny_boxes_through_its_table(blender, tmp_path):
    baked_objects(blender, 2)
    path = tmp_path / "far.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GODOT3") == {"FINISHED"}
    table = table_texels((tmp_path / "far.boxes.tres").read_text())
    assert len(table) >= 120
    numbers = []
    for mesh in read_glb(path):
        (p,) = mesh["primitives"]
        pos = p["POSITION"].astype(np.float64)
        colour = p["COLOR_0"].astype(np.float64)
        index = colour[:, 3]
        origins, axes, half = decode_normal_frame(pos, p["NORMAL"].astype(np.float64),
                                                  p["TANGENT"].astype(np.float64), colour[:, :3],
                                                  table[index.astype(int), :3])
        errors = check_boxes(pos, origins, axes, half, index)
        assert errors[0] < BOUND and errors[1] < BOUND, errors
        numbers.append(np.unique(index))
    assert np.array_equal(np.concatenate(numbers), np.arange(120))


@pytest.mark.parametrize("preset, engine", [("UNITY", UNITY), ("UNREAL", UNREAL)])
def test_fbx_decodes_far_and_tiny_boxes_after_the_modelled_import(blender, tmp_path, preset, engine):
    baked_objects(blender, 1)
    path = tmp_path / "far.fbx"
    assert blender.ops.boxmarch.export(filepath=str(path), preset=preset) == {"FINISHED"}
    positions, uvs = imported(read_fbx_geometry(path), engine)
    origins, axes, half, index = decode_uv_frame(positions, uvs)
    errors = check_boxes(positions, origins, axes, half, index)
    assert errors[0] < BOUND and errors[1] < BOUND, errors


def test_the_check_fails_on_a_wrong_decode(blender, tmp_path):
    """Negative control: the same check, on the GLTF file decoded with the frame's y axis
    negated (a handedness slip), reports errors far above the bound."""
    baked_objects(blender, 1)
    path = tmp_path / "far.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    (p,) = read_glb(path)[0]["primitives"]
    pos = p["POSITION"].astype(np.float64)
    tangent = p["TANGENT"].astype(np.float64)
    tangent[:, 3] *= -1.0
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], 1).astype(np.float64)
    half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], 1).astype(np.float64)
    origins, axes, half = decode_normal_frame(pos, p["NORMAL"].astype(np.float64), tangent, offset, half)
    assert check_boxes(pos, origins, axes, half, p["TEXCOORD_2"][:, 1].astype(np.float64))[0] > 0.01

"""The add-on inside Blender (the bpy module): the bake operator on real meshes.

Stored data is read back from Blender and decoded here with the documented formula
(docs/FORMAT.md), independently of boxmarch's own decode helpers.
"""
import math

import numpy as np
import pytest

from boxmarch import scenes
from tests.conftest import mesh_object


def read_colour(mesh, name, raw_bytes=False):
    attr = mesh.color_attributes[name]
    count = len(mesh.vertices) if attr.domain == "POINT" else len(mesh.loops)
    buf = np.empty(count * 4, np.float32)
    attr.data.foreach_get("color_srgb" if raw_bytes else "color", buf)
    return buf.reshape(-1, 4)


def read_uv(mesh, name):
    layer = mesh.uv_layers[name]
    buf = np.empty(len(mesh.loops) * 2, np.float32)
    layer.uv.foreach_get("vector", buf)
    return buf.reshape(-1, 2)


def read_positions(mesh):
    buf = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", buf)
    return buf.reshape(-1, 3)


def corner_verts_of(mesh):
    buf = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", buf)
    return buf


def decode_corners(mesh, raw_bytes=False):
    """Origin seen from every corner: position + rotate(q, (rgb * 2 - 1) / a), in float64."""
    corner_verts = corner_verts_of(mesh)
    colour = read_colour(mesh, "BoxOffset", raw_bytes).astype(np.float64)
    if mesh.color_attributes["BoxOffset"].domain == "POINT":
        colour = colour[corner_verts]
    if raw_bytes:
        colour = np.rint(colour * 255.0) / 255.0  # what a GPU reads from normalised bytes
    f = (colour[:, :3] * 2.0 - 1.0) / colour[:, 3:4]
    q = np.concatenate([read_uv(mesh, "BoxQuatXY"), read_uv(mesh, "BoxQuatZW")], axis=1).astype(np.float64)
    u, w = q[:, :3], q[:, 3:4]
    rotated = f + 2.0 * np.cross(u, np.cross(u, f) + w * f)
    return read_positions(mesh).astype(np.float64)[corner_verts] + rotated, q


def box_scene(blender, count=50, seed=1, name="boxes", spread=20.0, size_range=(0.2, 3.0)):
    arrays, centres, sizes, rotations = scenes.random_boxes(count, seed=seed, spread=spread, size_range=size_range)
    return mesh_object(blender, name, *arrays), centres, sizes


def test_bake_operator_decodes_to_box_centres(blender):
    ob, centres, sizes = box_scene(blender)
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    mesh = ob.data
    names = [uv.name for uv in mesh.uv_layers]
    assert names == ["UVMap", "BoxQuatXY", "BoxQuatZW"]  # quaternion in channels 1 and 2, as the blog post's shader reads it
    origins, q = decode_corners(mesh)
    truth = np.repeat(centres, 24, axis=0)
    half = np.repeat(sizes.max(axis=1) / 2, 24)
    # float32 storage of the vertices themselves limits the truth to ~|centre| * 2^-23
    assert np.all(np.linalg.norm(origins - truth, axis=1) <= 1e-5 * half + 4e-6 * np.abs(truth).max())
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    assert np.all(q[:, 3] >= 0)


def test_byte_colour_stores_raw_bytes_and_alpha_at_most_one(blender):
    ob, centres, sizes = box_scene(blender, size_range=(2.0, 6.0))
    assert blender.ops.boxmarch.bake(encoding="BYTE_COLOR") == {"FINISHED"}
    mesh = ob.data
    assert mesh.color_attributes["BoxOffset"].data_type == "BYTE_COLOR"
    raw = read_colour(mesh, "BoxOffset", raw_bytes=True) * 255.0
    assert np.allclose(raw, np.rint(raw), atol=1e-3)  # exactly bytes, no colour curve applied
    assert raw[:, 3].max() <= 255.0
    origins, _ = decode_corners(mesh, raw_bytes=True)
    truth = np.repeat(centres, 24, axis=0)
    half = np.repeat(sizes.max(axis=1) / 2, 24)
    # 8 bits: a quantisation step of 2 / 255 of the scaled offset, a few percent of the half-extent
    assert np.all(np.linalg.norm(origins - truth, axis=1) <= 0.02 * half)


def test_corner_domain_and_mean_origin(blender):
    ob, centres, _ = box_scene(blender, count=10)
    assert blender.ops.boxmarch.bake(domain="CORNER", origin="MEAN") == {"FINISHED"}
    mesh = ob.data
    assert mesh.color_attributes["BoxOffset"].domain == "CORNER"
    origins, _ = decode_corners(mesh)
    mean = read_positions(mesh).astype(np.float64).reshape(-1, 8, 3).mean(axis=1)
    assert np.allclose(origins, np.repeat(mean, 24, axis=0), atol=1e-5)


def test_artist_colours_and_uvs_are_left_alone(blender):
    ob, _, _ = box_scene(blender, count=5)
    mesh = ob.data
    paint = mesh.color_attributes.new("Paint", "FLOAT_COLOR", "POINT")
    mesh.color_attributes.active_color = paint
    values = np.random.default_rng(0).random(len(mesh.vertices) * 4).astype(np.float32)
    mesh.color_attributes["Paint"].data.foreach_set("color", values)
    mesh.uv_layers.new(name="Artist")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    assert np.array_equal(read_colour(mesh, "Paint").reshape(-1), values)
    assert mesh.color_attributes.active_color.name == "Paint"
    assert [uv.name for uv in mesh.uv_layers] == ["Artist", "BoxQuatXY", "BoxQuatZW"]


def test_edit_mode_bakes_submeshes_with_a_selected_vertex(blender):
    ob, centres, _ = box_scene(blender, count=3)
    blender.ops.object.mode_set(mode="EDIT")
    blender.ops.mesh.select_all(action="DESELECT")
    blender.ops.object.mode_set(mode="OBJECT")
    select = np.zeros(len(ob.data.vertices), bool)
    select[9] = True  # one vertex of box 1
    ob.data.vertices.foreach_set("select", select)
    blender.ops.object.mode_set(mode="EDIT")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    assert blender.context.mode == "EDIT_MESH"
    blender.ops.object.mode_set(mode="OBJECT")
    origins, q = decode_corners(ob.data)
    assert np.allclose(origins[24:48], centres[1], atol=1e-5)
    # untouched boxes hold the neutral encoding: f = 0 and the identity quaternion
    assert np.allclose(origins[:24], read_positions(ob.data)[corner_verts_of(ob.data)[:24]], atol=1e-6)
    assert np.allclose(q[:24], [0, 0, 0, 1])
    # a second edit-mode bake of box 2 keeps box 1's values
    select[:] = False
    select[17] = True
    ob.data.vertices.foreach_set("select", select)
    blender.ops.object.mode_set(mode="EDIT")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    origins, _ = decode_corners(ob.data)
    assert np.allclose(origins[24:72], np.repeat(centres[1:3], 24, axis=0), atol=1e-5)


def test_multi_object_edit_mode(blender):
    a, ca, _ = box_scene(blender, count=2, seed=3, name="A")
    b, cb, _ = box_scene(blender, count=2, seed=4, name="B")
    for ob in (a, b):
        ob.select_set(True)
    blender.ops.object.mode_set(mode="EDIT")
    blender.ops.mesh.select_all(action="SELECT")
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    for ob, centres in ((a, ca), (b, cb)):
        origins, _ = decode_corners(ob.data)
        assert np.allclose(origins, np.repeat(centres, 24, axis=0), atol=1e-5)


@pytest.mark.parametrize("encoding, domain, tolerance", [("FLOAT_COLOR", "POINT", 1e-5),
                                                         ("BYTE_COLOR", "CORNER", 0.05)])
def test_rebake_skips_unchanged_submeshes(blender, encoding, domain, tolerance):
    from boxmarch import mesh_io

    ob, centres, sizes = box_scene(blender, count=20)
    settings = mesh_io.BakeSettings(encoding=encoding, domain=domain)
    mesh_io.prepare_bake(ob.data, settings).write()
    positions = read_positions(ob.data)
    positions[8:16] += np.float32(5.0)  # move box 1
    ob.data.vertices.foreach_set("co", positions.reshape(-1))
    ob.data.update()
    prepared = mesh_io.prepare_bake(ob.data, settings)
    assert (prepared.result.baked, prepared.result.unchanged) == (1, 19)
    prepared.write()
    origins, _ = decode_corners(ob.data, raw_bytes=encoding == "BYTE_COLOR")
    expected = centres.copy()
    expected[1] += 5.0
    miss = np.linalg.norm(origins - np.repeat(expected, 24, axis=0), axis=1)
    assert (miss <= tolerance * np.repeat(sizes.max(axis=1), 24)).all()
    # changing an option re-bakes everything
    settings.origin = "MEAN"
    assert mesh_io.prepare_bake(ob.data, settings).result.baked == 20


def test_axis_turn_and_sort_keep_decode_exact(blender):
    ob, centres, _ = box_scene(blender, count=10)
    for turn in ("0", "7", "23"):
        assert blender.ops.boxmarch.bake(axis_turn=turn, sort_axes_by_extent=True, incremental=False) == {"FINISHED"}
        origins, _ = decode_corners(ob.data)
        assert np.allclose(origins, np.repeat(centres, 24, axis=0), atol=1e-5)


def attribute_names(mesh):
    return sorted(a.name for a in mesh.attributes) + [uv.name for uv in mesh.uv_layers]


@pytest.mark.parametrize("case", ["nan", "inf", "empty", "loose_vertices", "loose_edges"])
def test_bad_meshes_are_refused_and_left_untouched(blender, case):
    if case in ("nan", "inf"):
        ob, _, _ = box_scene(blender, count=3)
        positions = read_positions(ob.data)
        positions[5, 1] = np.nan if case == "nan" else np.inf
        ob.data.vertices.foreach_set("co", positions.reshape(-1))
    elif case == "empty":
        ob = mesh_object(blender, "empty", np.zeros((0, 3)), np.zeros((0, 2)), [], [], [])
    elif case == "loose_vertices":
        ob = mesh_object(blender, "points", np.eye(3), np.zeros((0, 2)), [], [], [])
    else:
        ob = mesh_object(blender, "wire", np.eye(3), [[0, 1], [1, 2]], [], [], [])
    before = attribute_names(ob.data)
    with pytest.raises(RuntimeError) as error:
        blender.ops.boxmarch.bake()
    message = str(error.value)
    assert "Nothing baked" in message
    assert {"nan": "NaN", "inf": "infinite", "empty": "empty", "loose_vertices": "no faces",
            "loose_edges": "no faces"}[case] in message
    assert attribute_names(ob.data) == before


def test_one_bad_mesh_stops_the_whole_bake(blender):
    good, _, _ = box_scene(blender, count=2, name="good")
    bad, _, _ = box_scene(blender, count=2, name="bad")
    positions = read_positions(bad.data)
    positions[0, 0] = np.nan
    bad.data.vertices.foreach_set("co", positions.reshape(-1))
    good.select_set(True)
    with pytest.raises(RuntimeError, match="bad"):
        blender.ops.boxmarch.bake()
    assert "BoxOffset" not in good.data.color_attributes


def test_no_mesh_selected(blender):
    empty = blender.data.objects.new("Empty", None)
    blender.context.scene.collection.objects.link(empty)
    empty.select_set(True)
    with pytest.raises(RuntimeError, match="Select at least one mesh"):
        blender.ops.boxmarch.bake()


def test_too_many_uv_maps_is_refused(blender):
    ob, _, _ = box_scene(blender, count=2)
    for i in range(7):
        ob.data.uv_layers.new(name=f"map{i}")
    before = attribute_names(ob.data)
    with pytest.raises(RuntimeError, match="UV maps"):
        blender.ops.boxmarch.bake()
    assert attribute_names(ob.data) == before


def test_degenerate_submeshes_bake_finite(blender):
    # a box, a lone triangle and a flat quad in one mesh: fallbacks are counted, nothing is NaN
    (p, e, fs, fz, cv), centres, _, _ = scenes.random_boxes(1, seed=5, spread=1.0)
    tri = np.array([[10, 0, 0], [11, 0, 0], [10, 1, 0]], np.float32)
    quad = np.array([[20, 0, 0], [21, 0, 0], [21, 1, 0], [20, 1, 0]], np.float32)
    positions = np.concatenate([p, tri, quad])
    corner_verts = np.concatenate([cv, [8, 9, 10], [11, 12, 13, 14]]).astype(np.int32)
    face_starts = np.concatenate([fs, [24, 27]]).astype(np.int32)
    face_sizes = np.concatenate([fz, [3, 4]]).astype(np.int32)
    ob = mesh_object(blender, "mixed", positions, e, face_starts, face_sizes, corner_verts)
    from boxmarch import mesh_io

    prepared = mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings())
    assert prepared.result.degenerate == 2
    prepared.write()
    origins, q = decode_corners(ob.data)
    assert np.all(np.isfinite(origins)) and np.all(np.isfinite(q))
    assert np.allclose(origins[:24], centres[0], atol=1e-5)
    # the triangle's frame: its normal and its longest edge (the hypotenuse, along (-1, 1, 0));
    # its bounds in that frame span 1/sqrt(2) along the hypotenuse and 1/sqrt(8) across it,
    # centred on the point halfway between the hypotenuse's midpoint (10.5, 0.5) and (10, 0)
    assert np.allclose(origins[24:27], [10.25, 0.25, 0], atol=1e-5)
    assert np.allclose(origins[27:], [20.5, 0.5, 0], atol=1e-5)


def test_operator_is_registered_for_search_and_menus(blender):
    op = blender.types.BOXMARCH_OT_bake
    assert {"REGISTER", "UNDO"} <= set(op.bl_options)
    assert op.bl_label == "Bake Box Frames"
    angle_epsilon = blender.ops.boxmarch.bake.get_rna_type().properties["angle_epsilon"]
    assert math.isclose(angle_epsilon.default, 0.1, rel_tol=1e-6)
    # The core's range (float32 values, held exactly by the property): the limits accept nothing
    # the core refuses.
    from boxmarch import core

    assert (angle_epsilon.hard_min, angle_epsilon.hard_max) == core.ANGLE_EPSILON_RANGE
    assert blender.types.BOXMARCH_PT_bake.bl_category == "Boxmarch"


def test_new_mesh_edges_have_a_readable_selection(blender):
    """Blender 5.0.1 gives edges it derives an INT32_2D '.select_edge' that crashes edge-selection
    access; meshes from mesh_io.new_mesh must not carry it."""
    from boxmarch import mesh_io

    (positions, _edges, face_starts, face_sizes, corner_verts), *_ = scenes.random_boxes(3)
    mesh = mesh_io.new_mesh("derived", positions, face_starts, face_sizes, corner_verts)
    assert all(a.data_type == "BOOLEAN" for a in mesh.attributes if a.name.startswith(".select"))
    selected = np.ones(len(mesh.edges), bool)
    mesh.edges.foreach_get("select", selected)
    assert len(mesh.edges) == 36 and not selected.any()


def test_baking_a_copied_mesh_leaves_the_original_alone(blender):
    """Blender 4+ shares layer arrays between a mesh and its copy until one is written; the bake
    must write its own arrays, not the shared ones (Shift+D duplicates share them)."""
    ob, centres, _ = box_scene(blender, count=4)
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    before = {name: read_uv(ob.data, name).copy() for name in ("BoxQuatXY", "BoxQuatZW")}
    colour_before = read_colour(ob.data, "BoxOffset").copy()
    copy = ob.copy()
    copy.data = ob.data.copy()
    blender.context.scene.collection.objects.link(copy)
    positions = read_positions(copy.data)
    turn = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], np.float32)  # a quarter turn about z
    copy.data.vertices.foreach_set("co", (positions @ turn.T).reshape(-1))
    copy.data.update()
    ob.select_set(False)
    copy.select_set(True)
    blender.context.view_layer.objects.active = copy
    assert blender.ops.boxmarch.bake() == {"FINISHED"}
    for name, values in before.items():
        assert np.array_equal(read_uv(ob.data, name), values), name
    assert np.array_equal(read_colour(ob.data, "BoxOffset"), colour_before)
    origins, _ = decode_corners(copy.data)
    assert np.allclose(origins, np.repeat(centres @ turn.T.astype(np.float64), 24, axis=0), atol=1e-4)

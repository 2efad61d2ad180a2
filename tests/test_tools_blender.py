"""The submesh tool operators inside Blender (the bpy module) on meshes whose answer is known;
merge is compared with Blender's own Merge by Distance run on each submesh alone."""
import numpy as np
import pytest

from boxmarch import mesh_io, scenes
from tests.conftest import mesh_object
from tests.helpers.menus import drawn_operators


def faces_object(bpy, name, positions, starts, sizes, corners):
    """A selected, active object whose mesh holds these faces; Blender derives the edges."""
    ob = bpy.data.objects.new(name, mesh_io.new_mesh(name, positions, starts, sizes, corners))
    bpy.context.scene.collection.objects.link(ob)
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    return ob


def positions_of(mesh):
    buf = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", buf)
    return buf.reshape(-1, 3)


def flags(mesh, collection):
    """Selection per element, read from the internal attributes (absent: none selected)."""
    name = {"vertices": ".select_vert", "edges": ".select_edge", "polygons": ".select_poly"}[collection]
    buf = np.zeros(len(getattr(mesh, collection)), bool)
    if name in mesh.attributes:
        mesh.attributes[name].data.foreach_get("value", buf)
    return buf


def set_vertex_selection(bpy, ob, indices):
    bpy.ops.object.mode_set(mode="OBJECT")
    mesh = ob.data
    for name in (".select_vert", ".select_edge", ".select_poly"):  # no attribute: nothing selected
        if name in mesh.attributes:
            mesh.attributes.remove(mesh.attributes[name])
    select = np.zeros(len(mesh.vertices), bool)
    select[list(indices)] = True
    mesh.vertices.foreach_set("select", select)


def edit(bpy, *objects):
    bpy.ops.object.mode_set(mode="OBJECT")
    for ob in bpy.context.scene.objects:
        ob.select_set(ob in objects)
    bpy.context.view_layer.objects.active = objects[0]
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_mode(type="VERT")


def joined(*parts):
    """Mesh arrays of several box_arrays results in one mesh."""
    out = [[], [], [], [], []]
    vertices = corners = 0
    for positions, edges, starts, sizes, corner_verts in parts:
        out[0].append(positions)
        out[1].append(edges + vertices)
        out[2].append(starts + corners)
        out[3].append(sizes)
        out[4].append(corner_verts + vertices)
        vertices += len(positions)
        corners += len(corner_verts)
    return [np.concatenate(x) for x in out]


def test_select_linked_submeshes_in_multi_object_edit_mode(blender):
    a = mesh_object(blender, "A", *scenes.box_arrays(np.arange(4)[:, None] * [3.0, 0, 0], 1.0, np.eye(3)))
    b = mesh_object(blender, "B", *scenes.box_arrays(np.arange(3)[:, None] * [0, 3.0, 0], 1.0, np.eye(3)))
    set_vertex_selection(blender, a, [9, 27])
    set_vertex_selection(blender, b, [0])
    edit(blender, a, b)
    assert blender.ops.boxmarch.select_linked_submeshes() == {"FINISHED"}
    assert blender.context.mode == "EDIT_MESH"
    blender.ops.object.mode_set(mode="OBJECT")
    assert np.flatnonzero(flags(a.data, "vertices")).tolist() == list(range(8, 16)) + list(range(24, 32))
    assert np.flatnonzero(flags(a.data, "polygons")).tolist() == list(range(6, 12)) + list(range(18, 24))
    assert flags(a.data, "edges").sum() == 24
    assert np.flatnonzero(flags(b.data, "vertices")).tolist() == list(range(8))


@pytest.mark.parametrize("gap, count", [(0.0, 5), (0.98e-4, 5), (1.02e-4, 1)])
def test_select_linked_across_chains_touching_at_corners(blender, gap, count):
    centres = np.arange(5)[:, None] * np.array([1.0 + gap, 1.0, 1.0])
    ob = mesh_object(blender, "chain", *scenes.box_arrays(centres, 1.0, np.eye(3)))
    set_vertex_selection(blender, ob, [3])
    edit(blender, ob)
    assert blender.ops.boxmarch.select_linked_across(epsilon=1e-4) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert flags(ob.data, "vertices").sum() == 8 * count
    assert flags(ob.data, "polygons").sum() == 6 * count


def test_select_linked_across_near_zero_and_cell_borders(blender):
    # Boxes whose corners are 1e-9 apart exactly at 0 and at multiples of epsilon.
    eps = 1e-4
    parts = []
    for k, border in enumerate([0.0, eps, 2 * eps]):
        left = np.array([[border - 0.5 - 5e-10, 3.0 * k, 0.0]])
        parts += [scenes.box_arrays(left, 1.0, np.eye(3)), scenes.box_arrays(left + [1.0 + 1e-9, 0, 0], 1.0, np.eye(3))]
    ob = mesh_object(blender, "borders", *joined(*parts))
    set_vertex_selection(blender, ob, [0, 16, 32])
    edit(blender, ob)
    assert blender.ops.boxmarch.select_linked_across(epsilon=eps) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert flags(ob.data, "vertices").all()


def duplicated_boxes(count, jitter, seed=0):
    """``count`` random boxes, then a copy of each with every vertex moved by ``jitter``."""
    (positions, edges, starts, sizes, corners), _, _, _ = scenes.random_boxes(count, seed=seed, spread=10)
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=positions.shape)
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    copy = (positions.astype(np.float64) + jitter * direction).astype(np.float32)
    return joined((positions, edges, starts, sizes, corners), (copy, edges, starts, sizes, corners))


@pytest.mark.parametrize("jitter, deleted, vertex_group", [(1e-5, 20, False), (0.95e-4, 20, False),
                                                         (1.05e-4, 0, False), (1e-5, 20, True)])
def test_dedup_deletes_copies_within_tolerance(blender, jitter, deleted, vertex_group):
    """With a vertex group the mesh cannot be rebuilt from attributes: Blender's own delete runs
    on the planned selection instead, with the same result."""
    arrays = duplicated_boxes(20, jitter)
    ob = mesh_object(blender, "dups", *arrays)
    mesh = ob.data
    if vertex_group:
        ob.vertex_groups.new(name="weights").add(list(range(0, 160, 3)), 0.25, "REPLACE")
    paint = mesh.color_attributes.new("Paint", "FLOAT_COLOR", "POINT")
    colours = np.random.default_rng(1).random(len(mesh.vertices) * 4).astype(np.float32)
    paint.data.foreach_set("color", colours)
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    assert blender.ops.boxmarch.dedup_submeshes(tolerance=1e-4) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert len(mesh.vertices) == 8 * (40 - deleted)
    assert len(mesh.polygons) == 6 * (40 - deleted)
    # the kept originals are the first 20 boxes, unchanged, with their colours
    assert np.array_equal(positions_of(mesh)[:160], arrays[0][:160])
    kept = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.color_attributes["Paint"].data.foreach_get("color", kept)
    assert np.array_equal(kept[:640], colours[:640])
    assert flags(mesh, "vertices").all()  # the selection stays on what is left
    assert not [a.name for a in mesh.attributes if a.name.startswith("boxmarch")]
    if vertex_group:
        weighted = [v.index for v in mesh.vertices if v.groups]
        assert weighted == list(range(0, 160, 3))


def test_dedup_only_among_selected_submeshes_in_multi_object_edit(blender):
    a = mesh_object(blender, "A", *duplicated_boxes(5, 1e-6, seed=1))
    b = mesh_object(blender, "B", *duplicated_boxes(5, 1e-6, seed=2))
    set_vertex_selection(blender, a, [0, 8 * 5])        # box 0 and its copy
    set_vertex_selection(blender, b, [8, 16, 8 * 6])    # boxes 1, 2 and the copy of box 1
    edit(blender, a, b)
    assert blender.ops.boxmarch.dedup_submeshes() == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert (len(a.data.vertices), len(b.data.vertices)) == (72, 72)


def split_boxes(centres, jitter, seed=0):
    """Boxes (12 vertices, 6 quads each) whose +x face uses its own copies of corners 4 and 6 and
    whose +z face its own copies of corners 1 and 3, each moved by up to ``jitter``: still one
    connected submesh, and merging by distance restores an 8-vertex box."""
    n = len(centres)
    positions, _edges, starts, sizes, corners = scenes.box_arrays(centres, 1.0, np.eye(3))
    originals = positions.reshape(n, 8, 3)
    rng = np.random.default_rng(seed)
    copies = originals[:, [4, 6, 1, 3]] + rng.uniform(-jitter, jitter, (n, 4, 3)).astype(np.float32)
    quads = np.array([[0, 1, 3, 2], [8, 9, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [10, 5, 7, 11]])
    corner_verts = (quads[None] + 12 * np.arange(n)[:, None, None]).reshape(-1).astype(np.int32)
    return np.concatenate([originals, copies], axis=1).reshape(-1, 3), starts, sizes, corner_verts


def blender_merge_per_submesh(bpy, arrays, distance, submesh_count, merged_positions=None):
    """Vertex, edge and face counts of Blender's own Merge by Distance on each submesh alone
    (and, into ``merged_positions`` when given, the vertex positions it leaves)."""
    positions, starts, sizes, corners = arrays
    totals = np.zeros(3, int)
    for s in range(submesh_count):
        part = faces_object(bpy, f"part{s}", positions[12 * s:12 * (s + 1)], starts[:6], sizes[:6],
                            corners[24 * s:24 * (s + 1)] - 12 * s)
        edit(bpy, part)
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.mesh.remove_doubles(threshold=distance)
        bpy.ops.object.mode_set(mode="OBJECT")
        totals += [len(part.data.vertices), len(part.data.edges), len(part.data.polygons)]
        if merged_positions is not None:
            merged_positions.append(positions_of(part.data))
        bpy.data.objects.remove(part)
    return totals


def test_merge_per_submesh_equals_blenders_merge_of_each_submesh(blender):
    # A row of boxes touching at faces: a whole-mesh merge would weld neighbours together.
    centres = np.arange(6)[:, None] * np.array([1.0, 0, 0])
    distance = 1e-3
    arrays = split_boxes(centres, distance / 10)
    blender_positions = []
    expected = blender_merge_per_submesh(blender, arrays, distance, 6, blender_positions)
    ob = faces_object(blender, "split", *arrays)
    mesh = ob.data
    mesh.uv_layers.new(name="Artist")
    uv = np.random.default_rng(0).random(len(mesh.loops) * 2).astype(np.float32)
    mesh.uv_layers["Artist"].uv.foreach_set("vector", uv)
    paint = mesh.color_attributes.new("Paint", "FLOAT_COLOR", "POINT")
    paint.data.foreach_set("color", np.repeat(np.arange(len(mesh.vertices), dtype=np.float32), 4))
    mat_a, mat_b = blender.data.materials.new("a"), blender.data.materials.new("b")
    mesh.materials.append(mat_a)
    mesh.materials.append(mat_b)
    material = np.tile([0, 1, 0, 1, 0, 1], 6).astype(np.int32)
    mesh.polygons.foreach_set("material_index", material)
    set_vertex_selection(blender, ob, [0])  # only box 0 ...
    edit(blender, ob)
    blender.ops.boxmarch.select_linked_submeshes()
    blender.ops.mesh.select_all(action="SELECT")  # ... then everything
    assert blender.ops.boxmarch.merge_by_distance_submeshes(distance=distance) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    counts = [len(mesh.vertices), len(mesh.edges), len(mesh.polygons)]
    assert counts == expected.tolist() == [48, 72, 36]
    # the same vertex positions as Blender 5.0 leaves (merged ones at their cluster's centroid);
    # which member of a cluster survives, and so the order, follows Blender's k-d tree and may
    # differ. Blender 4.2 and 4.5 leave that member where it was: each position is then within
    # the merge distance of one of theirs.
    ours, theirs = positions_of(mesh), np.concatenate(blender_positions)
    if blender.app.version >= (5, 0, 0):
        assert np.allclose(ours[np.lexsort(ours.T)], theirs[np.lexsort(theirs.T)], atol=1e-7)
    else:
        gaps = np.linalg.norm(ours[:, None] - theirs[None], axis=2)
        assert gaps.min(axis=1).max() <= distance and gaps.min(axis=0).max() <= distance
        assert not np.allclose(ours[np.lexsort(ours.T)], theirs[np.lexsort(theirs.T)], atol=1e-7)
    # no degenerate face: every face has 4 distinct vertices
    corner_verts = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_verts)
    assert all(len(set(f.vertices)) == len(f.vertices) for f in mesh.polygons)
    # attributes survive: UVs per corner (faces were not re-cornered), colours of the kept
    # vertices, materials per face
    after_uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers["Artist"].uv.foreach_get("vector", after_uv)
    assert np.array_equal(np.sort(after_uv), np.sort(uv))
    colour = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.color_attributes["Paint"].data.foreach_get("color", colour)
    assert set(colour[::4].astype(int)) <= set(range(12 * 6)) and len(set(colour[::4])) == 48
    after_material = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", after_material)
    assert np.array_equal(np.sort(after_material), np.sort(material))
    # the tool's helper attributes are gone and the selection is back
    assert not [a.name for a in mesh.attributes if a.name.startswith("boxmarch")]
    assert flags(mesh, "vertices").all()


@pytest.mark.parametrize("case", ["vertex_group", "face_split"])
def test_merge_falls_back_to_blenders_merge_and_still_matches(blender, case):
    """Where a rebuild could lose data (vertex groups) or Blender's weld does more than drop
    corners (a quad whose opposite corners merge is split), the tool runs Blender's own merge on
    a planned selection, pass by pass: counts still equal Blender's merge of each submesh."""
    centres = np.arange(4)[:, None] * np.array([1.0, 0, 0])
    distance = 1e-3
    positions, starts, sizes, corners = split_boxes(centres, distance / 10)
    if case == "face_split":
        # box 0's -x face [0, 1, 3, 2]: corner 3 moved onto corner 0 (opposite corners)
        positions = positions.copy()
        positions[3] = positions[0] + 1e-5
    arrays = (positions, starts, sizes, corners)
    expected = blender_merge_per_submesh(blender, arrays, distance, 4)
    ob = faces_object(blender, "split", *arrays)
    if case == "vertex_group":
        group = ob.vertex_groups.new(name="weights")
        group.add(list(range(0, len(positions), 2)), 0.5, "REPLACE")
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    assert blender.ops.boxmarch.merge_by_distance_submeshes(distance=distance) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    mesh = ob.data
    assert [len(mesh.vertices), len(mesh.edges), len(mesh.polygons)] == expected.tolist()
    assert not [a.name for a in mesh.attributes if a.name.startswith("boxmarch")]
    assert flags(mesh, "vertices").all()
    if case == "vertex_group":
        assert sum(1 for v in mesh.vertices if v.groups) > 0


def test_merge_and_dedup_on_wire_meshes(blender):
    # a polyline whose vertex 2 is doubled (2 and 3 within the distance): one vertex and one
    # edge go; a copy of the whole polyline 1e-6 away is a duplicate submesh
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0, 1e-5], [3, 0, 0]], np.float32)
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]], np.int32)
    ob = mesh_object(blender, "wire", np.concatenate([line, line + 1e-6]), np.concatenate([edges, edges + 5]),
                     [], [], [])
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    assert blender.ops.boxmarch.dedup_submeshes() == {"FINISHED"}
    assert blender.ops.boxmarch.merge_by_distance_submeshes(distance=1e-3) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert (len(ob.data.vertices), len(ob.data.edges)) == (4, 3)


def test_merge_only_touches_selected_submeshes(blender):
    arrays = split_boxes(np.arange(3)[:, None] * np.array([3.0, 0, 0]), 1e-4)
    ob = faces_object(blender, "split", *arrays)
    set_vertex_selection(blender, ob, [12])  # box 1
    edit(blender, ob)
    assert blender.ops.boxmarch.merge_by_distance_submeshes(distance=1e-3) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    assert len(ob.data.vertices) == 32
    assert np.flatnonzero(flags(ob.data, "vertices")).tolist() == [12]


def test_dedup_and_merge_in_object_mode_work_on_whole_meshes(blender):
    """Object Mode (scripts, the command line): whole meshes of the selected objects."""
    dups = mesh_object(blender, "dups", *duplicated_boxes(4, 1e-6))
    split = faces_object(blender, "split", *split_boxes(np.arange(3)[:, None] * np.array([1.0, 0, 0]), 1e-4))
    for ob in (dups, split):
        ob.select_set(True)
        set_vertex_selection(blender, ob, [0])
    assert blender.context.mode == "OBJECT"
    assert blender.ops.boxmarch.dedup_submeshes() == {"FINISHED"}
    assert blender.ops.boxmarch.merge_by_distance_submeshes(distance=1e-3) == {"FINISHED"}
    assert blender.context.mode == "OBJECT"
    assert (len(dups.data.vertices), len(split.data.vertices)) == (32, 24)
    assert blender.context.view_layer.objects.active == split
    assert sorted(ob.name for ob in blender.context.selected_objects) == ["dups", "split"]
    assert flags(dups.data, "vertices").sum() == 1 and flags(split.data, "vertices").sum() == 1


def uv_islands_mesh(bpy, count=30, seed=0):
    (positions, edges, starts, sizes, corners), _, _, _ = scenes.random_boxes(count, seed=seed, spread=10)
    ob = mesh_object(bpy, "uv", positions, edges, starts, sizes, corners)
    ob.data.uv_layers.new(name="Atlas")
    rng = np.random.default_rng(seed)
    faces = len(starts)
    size = rng.uniform(0.1, 1.0, (faces, 1, 2))
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)[None]
    uv = (rng.uniform(0, 3, (faces, 1, 2)) + square * size).reshape(-1).astype(np.float32)
    ob.data.uv_layers["Atlas"].uv.foreach_set("vector", uv)
    return ob, uv.reshape(-1, 2)


def test_pack_uv_by_z_selected_faces_inside_square_without_overlap(blender):
    ob, before = uv_islands_mesh(blender)
    ob.location.z = 100.0  # world Z decides, and every submesh moves alike
    faces = len(ob.data.polygons)
    set_vertex_selection(blender, ob, range(0, 8 * 20))  # boxes 0-19: their faces get selected
    edit(blender, ob)
    assert blender.ops.boxmarch.pack_uv_by_z(padding=0.005, max_per_row=9, uv_map="Atlas") == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    uv = np.empty(len(ob.data.loops) * 2, np.float32)
    ob.data.uv_layers["Atlas"].uv.foreach_get("vector", uv)
    uv = uv.reshape(faces, 4, 2).astype(np.float64)
    packed = uv[:120]
    assert np.array_equal(uv[120:], before.reshape(faces, 4, 2)[120:])  # unselected faces untouched
    lo, hi = packed.min(1), packed.max(1)
    assert lo.min() >= 0.005 - 1e-6 and hi.max() <= 1 - 0.005 + 1e-6
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]).max(-1)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= 0.005 - 1e-6
    z = positions_of(ob.data)[:160, 2].reshape(20, 8).astype(np.float64)
    face_z = np.repeat((z.min(1) + z.max(1)) / 2, 6)
    top_first = np.argsort(-face_z, kind="stable")
    bottoms = np.round(lo[top_first, 1], 5)
    assert np.all(np.diff(bottoms) <= 1e-5)  # rows go down as Z goes down
    assert np.unique(bottoms, return_counts=True)[1].max() <= 9


def test_pack_uv_by_z_packs_multi_object_edit_into_one_square(blender):
    a, _ = uv_islands_mesh(blender, count=10, seed=1)
    b, _ = uv_islands_mesh(blender, count=10, seed=2)
    b.location.z = 50.0  # every submesh of b is higher: b's islands fill the top rows
    edit(blender, a, b)
    blender.ops.mesh.select_all(action="SELECT")
    assert blender.ops.boxmarch.pack_uv_by_z(padding=0.003) == {"FINISHED"}
    blender.ops.object.mode_set(mode="OBJECT")
    boxes = []
    for ob in (a, b):
        uv = np.empty(len(ob.data.loops) * 2, np.float32)
        ob.data.uv_layers["Atlas"].uv.foreach_get("vector", uv)
        uv = uv.reshape(-1, 4, 2).astype(np.float64)
        boxes.append((uv.min(1), uv.max(1)))
    lo = np.concatenate([boxes[0][0], boxes[1][0]])
    hi = np.concatenate([boxes[0][1], boxes[1][1]])
    assert lo.min() >= 0.003 - 1e-6 and hi.max() <= 1 - 0.003 + 1e-6
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :]).max(-1)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= 0.003 - 1e-6  # no island of one object overlaps one of the other
    # rows are bottom-aligned: every row of b is at or above every row of a
    assert boxes[1][0][:, 1].min() >= boxes[0][0][:, 1].max() - 1e-6


def test_pack_uv_without_uv_map_or_faces_is_refused(blender):
    ob = mesh_object(blender, "plain", *scenes.box_arrays(np.zeros((1, 3)), 1.0, np.eye(3)))
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    with pytest.raises(RuntimeError, match="no UV map"):
        blender.ops.boxmarch.pack_uv_by_z()
    blender.ops.object.mode_set(mode="OBJECT")
    mesh_object(blender, "wire", np.eye(3), [[0, 1], [1, 2]], [], [], [])
    with pytest.raises(RuntimeError, match="no faces"):
        blender.ops.boxmarch.pack_uv_by_z()


@pytest.mark.parametrize("operator, args", [("select_linked_across", {"epsilon": -1.0}),
                                            ("select_linked_across", {"epsilon": float("nan")}),
                                            ("dedup_submeshes", {"tolerance": -1e-4}),
                                            ("merge_by_distance_submeshes", {"distance": float("nan")})])
def test_bad_values_are_refused(blender, operator, args):
    ob = mesh_object(blender, "boxes", *duplicated_boxes(3, 1e-6))
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    with pytest.raises(RuntimeError, match="Nothing changed"):
        getattr(blender.ops.boxmarch, operator)(**args)
    blender.ops.object.mode_set(mode="OBJECT")
    assert len(ob.data.vertices) == 48


@pytest.mark.parametrize("operator", ["select_linked_submeshes", "select_linked_across", "dedup_submeshes",
                                      "merge_by_distance_submeshes", "pack_uv_by_z"])
def test_nan_meshes_are_refused_and_left_unchanged(blender, operator):
    arrays = duplicated_boxes(3, 1e-6)
    arrays[0][5, 1] = np.nan
    ob = mesh_object(blender, "nan", *arrays)
    ob.data.uv_layers.new(name="UVMap")
    edit(blender, ob)
    blender.ops.mesh.select_all(action="SELECT")
    with pytest.raises(RuntimeError, match="NaN"):
        getattr(blender.ops.boxmarch, operator)()
    blender.ops.object.mode_set(mode="OBJECT")
    assert len(ob.data.vertices) == 48


@pytest.mark.parametrize("operator", ["select_linked_submeshes", "select_linked_across", "dedup_submeshes",
                                      "merge_by_distance_submeshes", "pack_uv_by_z"])
def test_empty_selection_is_refused(blender, operator):
    ob = mesh_object(blender, "boxes", *duplicated_boxes(3, 1e-6))
    ob.data.uv_layers.new(name="UVMap")
    edit(blender, ob)
    blender.ops.mesh.select_all(action="DESELECT")
    with pytest.raises(RuntimeError, match="no (vertex|face) is selected"):
        getattr(blender.ops.boxmarch, operator)()
    blender.ops.object.mode_set(mode="OBJECT")
    assert len(ob.data.vertices) == 48


def test_no_mesh_is_refused(blender):
    empty = blender.data.objects.new("Empty", None)
    blender.context.scene.collection.objects.link(empty)
    empty.select_set(True)
    with pytest.raises(RuntimeError, match="Select at least one mesh"):
        blender.ops.boxmarch.dedup_submeshes()


def test_instance_on_curve_evaluates_axis_aligned_copies(blender):
    blender.ops.mesh.primitive_cube_add(size=0.5, location=(7, 7, 7), rotation=(0.3, 0.2, 0.1))
    cube = blender.context.active_object
    blender.ops.curve.primitive_nurbs_path_add()  # a straight path of length 4 along x
    curve = blender.context.active_object
    assert blender.ops.boxmarch.add_instance_on_curve(instance=cube.name, spacing=0.5) == {"FINISHED"}
    assert any(m.type == "NODES" and m.node_group.name == "Boxmarch Instance On Curve" for m in curve.modifiers)
    depsgraph = blender.context.evaluated_depsgraph_get()
    evaluated = curve.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        points = positions_of(mesh).reshape(-1, 8, 3).astype(np.float64)
        assert len(mesh.polygons) == 6 * len(points)
    finally:
        evaluated.to_mesh_clear()
    assert len(points) == 9  # 4 units at 0.5 spacing, both ends
    # each copy is the cube's own local geometry (its rotation is the object's, not the mesh's),
    # translated only: edges stay on the world axes, whatever the curve's direction
    local = positions_of(cube.data).astype(np.float64)
    offsets = points - local[None]
    assert np.allclose(offsets, offsets[:, :1, :], atol=1e-5)
    assert np.allclose(np.diff(offsets[:, 0, 0]), 0.5, atol=1e-4)
    # converted to a mesh, the packing runs on it
    assert blender.ops.boxmarch.add_instance_on_curve(instance=cube.name, spacing=0.5, convert_to_mesh=True) == {"FINISHED"}
    result = blender.context.active_object
    assert result.type == "MESH" and len(result.data.vertices) == 72
    assert blender.ops.boxmarch.pack_uv_by_z() == {"FINISHED"}


def test_instance_on_curve_refuses_bad_input(blender):
    blender.ops.mesh.primitive_cube_add()
    with pytest.raises(RuntimeError, match="not a curve"):
        blender.ops.boxmarch.add_instance_on_curve(instance="Cube")
    blender.ops.curve.primitive_nurbs_path_add()
    with pytest.raises(RuntimeError, match="No object named"):
        blender.ops.boxmarch.add_instance_on_curve(instance="Missing")


@pytest.mark.slow
@pytest.mark.blender_program
def test_tools_and_undo_in_blender_34_window(tmp_path):
    """Debian's Blender 3.4 with a window under Xvfb (the bpy module has no window, so undo needs
    the program): every tool runs there, changes the mesh, and one undo restores it; the mesh's
    Skin modifier keeps its radii layer through every tool."""
    import json
    import shutil
    import subprocess
    from pathlib import Path

    from tests.helpers.blender_program import SCRIPTS, blender_env

    import boxmarch

    if shutil.which("xvfb-run") is None or shutil.which("blender") is None:
        pytest.fail("xvfb-run or Debian's blender is missing: run scripts/setup.sh")
    parent = tmp_path / "path"
    parent.mkdir()
    (parent / "boxmarch").symlink_to(Path(boxmarch.__file__).parent, target_is_directory=True)
    out = tmp_path / "tools.json"
    proc = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", shutil.which("blender"),
                           "--factory-startup", "--python", str(SCRIPTS / "tools_undo_check.py"), "--",
                           str(parent), str(out)], env=blender_env(tmp_path), capture_output=True, text=True,
                          timeout=300)
    assert out.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads(out.read_text())
    assert result["error"] is None, result["error"]
    tools = result["tools"]
    for name, state in tools.items():
        assert state["result"] == ["FINISHED"] and state["undo_option"], name
        assert state["undone"] == state["before"] != state["after"], name
    assert tools["select_linked_submeshes"]["after"]["selected"] == 8  # box 0
    assert tools["select_linked_across"]["after"]["selected"] == 16    # box 0 and its copy 1e-6 away
    assert tools["dedup_submeshes"]["after"]["vertices"] == tools["dedup_submeshes"]["before"]["vertices"] - 8
    assert tools["merge_by_distance_submeshes"]["after"]["vertices"] == 40
    for name, state in tools.items():  # the Skin modifier's radii layer stays
        assert state["before"]["skin_layers"] == state["after"]["skin_layers"] == 1, name
    assert tools["pack_uv_by_z"]["after"]["uv_sum"] != tools["pack_uv_by_z"]["before"]["uv_sum"]
    curve = result["instance_on_curve"]
    assert curve["result"] == ["FINISHED"] and curve["evaluated_vertices"] == 72
    assert (curve["modifiers"], curve["modifiers_undone"]) == (1, 0)


def test_tools_are_in_the_menus_and_the_panel(blender):
    from boxmarch.operators import instance_on_curve, tools

    for menu_name, draw in tools.menus + instance_on_curve.menus:
        menu = getattr(blender.types, menu_name)
        ours = drawn_operators(draw)
        assert ours and set(ours) <= set(drawn_operators(menu.draw)), menu_name
        menu.remove(draw)  # negative control: without the add-on's item the menu lacks its operators
        try:
            assert not set(ours) & set(drawn_operators(menu.draw)), menu_name
        finally:
            menu.append(draw)
    assert hasattr(blender.types, "BOXMARCH_PT_submesh_tools")
    for idname in ("select_linked_submeshes", "select_linked_across", "dedup_submeshes",
                   "merge_by_distance_submeshes", "pack_uv_by_z", "add_instance_on_curve"):
        assert getattr(blender.types, "BOXMARCH_OT_" + idname).bl_options >= {"REGISTER", "UNDO"}

"""Per-box parameters and hierarchy through the bake in Blender: painted attributes in, the
stored layers read back raw (docs/FORMAT.md's names) and compared with what was painted."""
import numpy as np
import pytest

from boxmarch import bake_job, mesh_io, scenes
from tests.conftest import mesh_object

BOXES = 6


def chain_object(blender, name="chain"):
    """Six unit boxes along x, 1.5 apart: box i is submesh i (vertices 8i..8i+7, faces 6i..6i+5)."""
    centres = np.stack([1.5 * np.arange(BOXES), np.zeros(BOXES), np.zeros(BOXES)], 1)
    return mesh_object(blender, name, *scenes.box_arrays(centres, 1.0, np.eye(3)))


def paint(mesh, name, data_type, domain, values):
    attr = mesh.attributes.new(name, data_type, domain)
    prop = "color" if data_type == "FLOAT_COLOR" else ("color_srgb" if data_type == "BYTE_COLOR" else "value")
    attr.data.foreach_set(prop, np.asarray(values).reshape(-1))


# A layer not stored holds, per docs/FORMAT.md, this value at every vertex.
ABSENT_LAYER_VALUES = {".boxmarch_shape_material": 0.0, ".boxmarch_parent": -1, ".boxmarch_depth": 0}


def stored(mesh, name, data_type):
    n = len(mesh.vertices)
    attr = mesh.attributes.get(name)
    if attr is None and name in ABSENT_LAYER_VALUES:
        return np.full((n, 2) if data_type == "FLOAT2" else n, ABSENT_LAYER_VALUES[name],
                       np.float32 if data_type == "FLOAT2" else np.int32)
    assert attr.domain == "POINT" and attr.data_type == data_type
    buf = np.empty(n * 2 if data_type == "FLOAT2" else n, np.float32 if data_type == "FLOAT2" else np.int32)
    attr.data.foreach_get("vector" if data_type == "FLOAT2" else "value", buf)
    return buf.reshape(n, -1) if data_type == "FLOAT2" else buf


def stored_params(mesh):
    """(vertices, 4) shape, material, random, user as the bake stored them."""
    return np.concatenate([stored(mesh, ".boxmarch_shape_material", "FLOAT2"),
                           stored(mesh, ".boxmarch_random_user", "FLOAT2")], 1)


def bake(mesh, **settings):
    return bake_job.bake_meshes([mesh], mesh_io.BakeSettings(**settings))[0].report


def test_painted_parameters_and_parents_reach_the_stored_layers(blender):
    mesh = chain_object(blender).data
    shape = np.repeat(np.arange(BOXES), 6).astype(np.int32)  # per face
    shape[6 * 2 + 3] = 9  # one stray face on box 2: the box keeps its majority, the report counts it
    paint(mesh, "boxmarch_shape", "INT", "FACE", shape)
    user = np.repeat(0.25 + 0.125 * np.arange(BOXES), 8).astype(np.float32)  # per vertex
    paint(mesh, "boxmarch_user", "FLOAT", "POINT", user)
    material = np.repeat([3, 1, 4, 1, 5, 9], 24) / 255.0  # BYTE_COLOR corner colour: G carries the material byte
    colour = np.zeros((BOXES * 24, 4), np.float32)
    colour[:, 1] = material
    paint(mesh, "boxmarch_params", "BYTE_COLOR", "CORNER", colour)
    parent = np.repeat([-1, 0, 1, 2, 0, 4], 8).astype(np.int32)
    paint(mesh, "boxmarch_parent", "INT", "POINT", parent)
    report = bake(mesh)["boxes"]
    assert report["disagreeing_attributes"] == {"boxmarch_shape": {"submeshes": 1, "first": [2]}}
    assert report["max_depth"] == 3 and report["roots"] == 1

    params = stored_params(mesh)
    per_box = params[::8]
    assert np.array_equal(params, np.repeat(per_box, 8, axis=0))  # one value per box
    assert per_box[:, 0].tolist() == list(range(BOXES))
    assert np.allclose(per_box[:, 1], np.array([3, 1, 4, 1, 5, 9]) / 255.0, rtol=0, atol=1e-6)
    assert np.array_equal(per_box[:, 3], np.float32(0.25 + 0.125 * np.arange(BOXES)))
    assert np.all((per_box[:, 2] >= 0) & (per_box[:, 2] < 1)) and len(set(per_box[:, 2])) == BOXES
    assert stored(mesh, ".boxmarch_parent", "INT")[::8].tolist() == [-1, 0, 1, 2, 0, 4]
    assert stored(mesh, ".boxmarch_depth", "INT")[::8].tolist() == [0, 1, 2, 3, 1, 2]


def test_random_survives_a_rebake_and_a_repaint(blender):
    mesh = chain_object(blender).data
    bake(mesh, random_seed=5)
    # the stored parameters are no colour: BoxOffset stays the only, active and render colour
    assert [c.name for c in mesh.color_attributes] == ["BoxOffset"]
    assert mesh.color_attributes.active_color.name == "BoxOffset"
    first = stored_params(mesh)[::8, 2].copy()
    paint(mesh, "boxmarch_shape", "INT", "POINT", np.repeat(np.arange(BOXES), 8).astype(np.int32))
    report = bake(mesh, random_seed=5)
    assert report["unchanged"] == BOXES  # geometry untouched: skipped, the painted ids still written
    again = stored_params(mesh)[::8]
    assert np.array_equal(again[:, 2], first) and again[:, 0].tolist() == list(range(BOXES))
    bake(mesh, random_seed=6, incremental=False)
    assert np.mean(stored_params(mesh)[::8, 2] == first) < 0.5


@pytest.mark.parametrize("rule, parents", [("CHAIN", [-1, 0, 1, 2, 3, 4]), ("CONTAINMENT", [-1] * BOXES)])
def test_rules_from_geometry(blender, rule, parents):
    mesh = chain_object(blender).data
    bake(mesh, hierarchy=rule)
    assert stored(mesh, ".boxmarch_parent", "INT")[::8].tolist() == parents


def test_geometric_rules_see_the_unchanged_boxes_of_an_incremental_bake(blender):
    """Only box 3 moves (and is baked again): the other boxes' places come from the stored
    layers, so the chain is still found (with zeros in their place, box 3 would pick another)."""
    mesh = chain_object(blender).data
    bake(mesh, hierarchy="CHAIN")
    positions = mesh_io.read_positions(mesh)
    positions[24:32, 1] += 0.01
    mesh.vertices.foreach_set("co", positions.ravel())
    mesh.update()
    report = bake(mesh, hierarchy="CHAIN")
    assert report["baked"] == 1 and report["unchanged"] == BOXES - 1
    assert stored(mesh, ".boxmarch_parent", "INT")[::8].tolist() == [-1, 0, 1, 2, 3, 4]


def test_bad_parent_attribute_is_refused_and_nothing_written(blender):
    mesh = chain_object(blender).data
    paint(mesh, "boxmarch_parent", "INT", "POINT", np.repeat([1, 0, -1, -1, -1, -1], 8).astype(np.int32))
    with pytest.raises(mesh_io.BakeInputError, match="cycle"):
        bake(mesh)
    assert mesh.attributes.get(".boxmarch_shape_material") is None and mesh.color_attributes.get("BoxOffset") is None


@pytest.mark.parametrize("name, data_type, domain, values, message", [
    ("boxmarch_shape", "FLOAT", "POINT", np.r_[np.nan, np.zeros(47)], "NaN"),
    ("boxmarch_user", "FLOAT_VECTOR", "POINT", np.zeros(48 * 3), "FLOAT_VECTOR"),
    ("boxmarch_material", "INT", "EDGE", None, "EDGE"),
    ("boxmarch_params", "FLOAT", "POINT", np.zeros(48), "must be a colour"),
])
def test_unreadable_attributes_are_refused_and_nothing_written(blender, name, data_type, domain, values, message):
    mesh = chain_object(blender).data
    attr = mesh.attributes.new(name, data_type, domain)
    values = np.zeros(len(mesh.edges), np.int32) if values is None else values
    attr.data.foreach_set("vector" if data_type == "FLOAT_VECTOR" else "value", np.asarray(values).ravel())
    with pytest.raises(mesh_io.BakeInputError, match=message):
        bake(mesh)
    assert mesh.attributes.get(".boxmarch_shape_material") is None and mesh.color_attributes.get("BoxOffset") is None


def test_object_properties_give_what_no_attribute_paints(blender):
    ob = chain_object(blender)
    mesh = ob.data
    ob["boxmarch_shape"], ob["boxmarch_material"], ob["boxmarch_user"] = 4, 2.5, -0.75
    paint(mesh, "boxmarch_material", "INT", "POINT", np.repeat(np.arange(BOXES), 8).astype(np.int32))
    report = bake(mesh)["boxes"]
    per_box = stored_params(mesh)[::8]
    assert per_box[:, 0].tolist() == [4] * BOXES and per_box[:, 3].tolist() == [-0.75] * BOXES
    assert per_box[:, 1].tolist() == list(range(BOXES))  # the attribute wins over the property
    assert report["object_properties"] == {"boxmarch_shape": 4.0, "boxmarch_material": 2.5, "boxmarch_user": -0.75}


def test_linked_duplicates_must_agree_on_object_properties(blender):
    ob = chain_object(blender)
    twin = blender.data.objects.new("twin", ob.data)
    blender.context.scene.collection.objects.link(twin)
    ob["boxmarch_shape"], twin["boxmarch_shape"] = 3, 3
    bake(ob.data)
    assert stored_params(ob.data)[::8, 0].tolist() == [3] * BOXES
    twin["boxmarch_shape"] = 5
    with pytest.raises(mesh_io.BakeInputError, match="'chain' 3, 'twin' 5"):
        bake(ob.data, incremental=False)
    del twin["boxmarch_shape"]
    with pytest.raises(mesh_io.BakeInputError, match="'twin' none"):
        bake(ob.data)
    assert stored_params(ob.data)[::8, 0].tolist() == [3] * BOXES  # the refused bakes wrote nothing
    twin["boxmarch_shape"] = "gold"
    with pytest.raises(mesh_io.BakeInputError, match="property 'boxmarch_shape' is 'gold'"):
        bake(ob.data)


def bone_rule_expected(centres, bone_of_box, bone_parent):
    """The BONES rule worked out from the rig's known boxes: nearest box (by centre) of the
    parent bone, walking past bones without boxes; depths along the chain."""
    parent = []
    for i, bone in enumerate(bone_of_box):
        up = bone_parent[bone]
        while up >= 0 and up not in bone_of_box:
            up = bone_parent[up]
        candidates = [j for j in range(len(centres)) if up >= 0 and bone_of_box[j] == up]
        parent.append(min(candidates, key=lambda j: np.sum((centres[j] - centres[i]) ** 2)) if candidates else -1)
    depth = [0 if p < 0 else None for p in parent]
    while None in depth:
        depth = [d if d is not None else (depth[parent[i]] + 1 if depth[parent[i]] is not None else None)
                 for i, d in enumerate(depth)]
    return parent, depth


def test_bones_rule_on_the_rig(blender):
    """The 3-bone chain of tests/engine_scene.py, each box weighted to one bone: a box's parent
    is the nearest box of the previous bone. Then bone1's boxes go to bone2 and bone1 holds no
    box: bone2's boxes pass to bone0's."""
    from tests.engine_scene import rig_boxes, skinned_scene

    ob, rig = skinned_scene(blender)
    centres, _, _, bone_of_box = rig_boxes()
    vertices = len(ob.data.vertices)
    report = bake(ob.data, hierarchy="BONES")["boxes"]
    parent, depth = bone_rule_expected(centres, list(bone_of_box), [-1, 0, 1])
    assert stored(ob.data, ".boxmarch_parent", "INT")[::8].tolist() == parent
    assert stored(ob.data, ".boxmarch_depth", "INT")[::8].tolist() == depth
    assert report["max_depth"] == 2 and report["roots"] == int((bone_of_box == 0).sum())
    assert set(parent) != {-1} and parent != [-1] + list(range(len(parent) - 1))  # neither all roots nor CHAIN's

    moved = np.flatnonzero(np.repeat(bone_of_box, 8) == 1).tolist()
    ob.vertex_groups["bone1"].remove(moved)
    ob.vertex_groups["bone2"].add(moved, 1.0, "REPLACE")
    bake(ob.data, hierarchy="BONES")
    regrouped = np.where(bone_of_box == 1, 2, bone_of_box)
    parent, depth = bone_rule_expected(centres, list(regrouped), [-1, 0, 1])
    assert stored(ob.data, ".boxmarch_parent", "INT")[::8].tolist() == parent and max(depth) == 1
    assert len(stored(ob.data, ".boxmarch_parent", "INT")) == vertices


def test_bones_rule_without_a_rig_is_refused(blender):
    mesh = chain_object(blender).data
    with pytest.raises(mesh_io.BakeInputError, match="BONES rule needs"):
        bake(mesh, hierarchy="BONES")
    assert mesh.attributes.get(".boxmarch_parent") is None


def test_a_bake_with_nothing_painted_stores_only_the_random_values(blender):
    """What a scene does not need is not written: painted shapes and parents store their layers,
    and once the paint is gone the next bake removes them (absent: the defaults), leaving only the
    random values, which every box has."""
    mesh = chain_object(blender).data
    paint(mesh, "boxmarch_parent", "INT", "POINT", np.repeat([-1, 0, 1, 2, 3, 4], 8).astype(np.int32))
    paint(mesh, "boxmarch_shape", "INT", "POINT", np.full(BOXES * 8, 2, np.int32))
    bake(mesh)
    layers = (".boxmarch_shape_material", ".boxmarch_random_user", ".boxmarch_parent", ".boxmarch_depth")
    assert [name for name in layers if mesh.attributes.get(name) is not None] == list(layers)
    random = stored_params(mesh)[:, 2].copy()
    for name in ("boxmarch_parent", "boxmarch_shape"):
        mesh.attributes.remove(mesh.attributes[name])
    bake(mesh)
    assert [name for name in layers if mesh.attributes.get(name) is not None] == [".boxmarch_random_user"]
    boxes = mesh_io.read_box_layers(mesh, np.repeat(np.arange(BOXES), 8), BOXES)
    assert boxes.parent.tolist() == [-1] * BOXES and boxes.depth.tolist() == [0] * BOXES
    assert (boxes.params[:, [0, 1, 3]] == 0).all() and (boxes.params[:, 2] == random[::8]).all()

"""Every Layout's declared facts (formats/layouts.py) against what its encode writes: the decode of the
offset by its stated channels, where its quantities and box parameters ride, its channel list and
FBX UV names, and the sidecar schema's list of layouts. Expectations come from the inputs and an
independent quaternion rotation (tests/helpers/core_reference.py)."""
import json

import numpy as np
import pytest

from boxmarch.formats import layouts
from boxmarch.formats import sidecar
from tests.helpers.core_reference import quat_matrix

BOXES, PER_BOX = 5, 4


def _box_data(seed=0, quaternions=None):
    """Random boxes in object space: known frames, offsets, half-extents, parameters and parents."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(BOXES, 4)) if quaternions is None else quaternions
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1
    half = rng.uniform(0.2, 2.0, (BOXES, 3))
    box = np.repeat(np.arange(BOXES), PER_BOX)
    f = rng.uniform(-1, 1, (len(box), 3)) * half[box]
    scale = 1.0 / np.abs(f).max(axis=1)
    rgba = np.concatenate([0.5 + 0.5 * scale[:, None] * f, scale[:, None]], 1).astype(np.float32)
    params = rng.integers(0, 9, (BOXES, 4)).astype(np.float64)
    parent = np.array([-1, 0, 0, 1, 3])
    depth = np.array([0, 1, 1, 2, 3])
    data = layouts.BoxData(quaternions=q[box], offsets=f, half_extents=half[box], index=box.astype(np.int64),
                           classic_rgba=rgba, box_half_extents=half, box_params=params, box_parent=parent,
                           box_depth=depth, box_quaternions=q)
    return data, quat_matrix(q[box]) @ f[:, :, None]


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_the_stated_offset_and_frame_decode_to_the_box_origin(layout):
    data, expected = _box_data()
    channels = layouts.channels(layout, data)
    miss = np.abs(layouts.to_origin(layout, channels) - expected[:, :, 0]).max()
    assert miss < 1e-5
    # Negative control: the same offsets under other frames decode elsewhere.
    other, _ = _box_data(quaternions=np.random.default_rng(7).normal(size=(BOXES, 4)))
    wrong = dict(channels)
    for name in layouts.LAYOUTS[layout].quantities["frame"]["channels"]:
        channel = name.split(".")[0]
        wrong[channel] = layouts.channels(layout, other)[channel]
    assert np.abs(layouts.to_origin(layout, wrong) - expected[:, :, 0]).max() > 0.1


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_quantities_and_box_parameters_ride_where_the_layout_states(layout):
    spec = layouts.LAYOUTS[layout]
    data, _ = _box_data()
    channels = layouts.channels(layout, data)
    if spec.has_index:
        assert np.array_equal(layouts.component(channels, spec.quantities["index"]["channels"][0]), data.index)
    half = spec.quantities.get("half_extents")
    if half and half["encoding"] == "float":
        read = np.stack([layouts.component(channels, name) for name in half["channels"]], 1)
        assert np.allclose(read, data.half_extents, rtol=1e-6)
    elif half:
        assert np.allclose(channels["TABLE"][data.index, 0, :3], data.half_extents, rtol=1e-6)
    params, parent, depth = data.box_values()
    values = {"shape": params[:, 0], "material": params[:, 1], "random": params[:, 2], "user": params[:, 3],
              "parent": parent, "depth": depth}
    for name, where in sidecar.box_parameter_channels(layout).items():
        parts = where.split(".")
        if parts[0] == "TABLE":
            read = channels["TABLE"][data.index, int(parts[1]), "rgba".index(parts[2])]
        else:
            read = layouts.component(channels, where)
        assert np.array_equal(read, values[name][data.index]), (name, where)
    if not spec.has_table:
        assert "TABLE" not in channels and set(spec.param_channels.values()) >= {
            ("shape", "material"), ("random", "user"), ("parent", "depth")}


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_channel_list_uv_names_and_table_agree_with_the_encode(layout):
    spec = layouts.LAYOUTS[layout]
    channels = layouts.channels(layout, _box_data()[0])
    assert list(channels) == [*spec.channels, *(["TABLE"] if spec.has_table else [])]
    uvs = [name for name in spec.channels if name.startswith("UV")]
    assert uvs == [f"UV{n}" for n in range(1, spec.uv_channels + 1)]
    assert len(set(spec.uv_names)) == len(spec.uv_names)  # one FBX UV map per channel
    for quantity in spec.quantities.values():
        for name in quantity["channels"]:
            assert name.split(".")[0] in channels, name
    assert spec.skin_safe == ("NORMAL" in channels and "TANGENT" in channels)
    table = sidecar.table_path("/x/model.glb", layout, "GLTF")
    assert (table is not None) == spec.has_table


def test_the_schema_lists_every_layout_and_an_unknown_name_is_refused():
    with open(sidecar.SCHEMA_PATH) as f:
        schema = json.load(f)
    assert set(schema["properties"]["layout"]["enum"]) == set(layouts.LAYOUTS)
    with pytest.raises(ValueError, match="NORMAL_FRAME"):
        layouts.layout_named("NORMAL")
    with pytest.raises(ValueError, match="layout must be one of"):
        layouts.channels("NORMAL", _box_data()[0])

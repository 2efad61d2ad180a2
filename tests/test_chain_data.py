"""bench/chain_data.py keeps a chain's preview arrays compactly for the GPU machine: what it
stores expands to the arrays exactly, and arrays it cannot store so are refused."""
import numpy as np
import pytest

from bench import chain_data

PER_BOX, BOXES = 8, 6


def chain_arrays(rng):
    """Preview arrays of BOXES boxes: positions all different, a channel repeating every two
    boxes, one constant over each box, the file order's triangles repeating, an octant order."""
    box_triangles = rng.integers(0, PER_BOX, (chain_data.TRIANGLES_PER_BOX, 3)).astype(np.uint32)
    file_order = np.concatenate([box_triangles + PER_BOX * b for b in range(BOXES)])
    permutation = rng.permutation(BOXES)
    return {"input_names": np.array(["pos", "ch_uv1", "ch_half"]),
            "input_pos": rng.normal(size=(BOXES * PER_BOX, 3)).astype(np.float32),
            "input_ch_uv1": np.tile(rng.normal(size=(2 * PER_BOX, 2)), (BOXES // 2, 1)).astype(np.float32),
            "input_ch_half": np.repeat(rng.normal(size=(BOXES, 3)), PER_BOX, axis=0).astype(np.float32),
            "triangles_file": file_order,
            "triangles_octant": file_order.reshape(BOXES, -1, 3)[permutation].reshape(-1, 3)}


def test_what_is_stored_expands_to_the_arrays():
    arrays = chain_arrays(np.random.default_rng(0))
    stored = chain_data.compact(arrays, 2, PER_BOX)
    assert {"input_pos", "period_ch_uv1", "box_ch_half"} <= set(stored)
    assert len(stored["period_ch_uv1"]) == 2 * PER_BOX and len(stored["box_ch_half"]) == BOXES
    expanded = chain_data.expand(stored)
    for key in ("input_pos", "input_ch_uv1", "input_ch_half", "triangles_file", "triangles_octant"):
        assert np.array_equal(expanded[key], arrays[key]), key


def test_triangles_that_do_not_repeat_are_refused():
    arrays = chain_arrays(np.random.default_rng(1))
    arrays["triangles_file"] = arrays["triangles_file"].copy()
    arrays["triangles_file"][-1] = arrays["triangles_file"][-1][::-1]  # the last box's last triangle turned
    with pytest.raises(ValueError, match="do not repeat"):
        chain_data.compact(arrays, 2, PER_BOX)

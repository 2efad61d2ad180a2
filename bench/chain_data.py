"""A long chain's preview arrays stored compactly, so that 100,000 baked links travel to a GPU
machine in a few MiB (bench/gpu_frame_data.py writes, bench/bench_gpu_triangles.py reads).

The chain of bench_boxes_vs_triangles.chain_rows repeats two links (the second turned): a vertex
input either repeats with a period of two boxes (the frame's quaternion), or is the same over each
box's vertices (the half-extents, the per-box parameters, each rounded from its own bake), or
differs at every vertex (the positions, the CLASSIC colour's offsets); the file order's triangles
repeat (offset by two boxes' vertices) and the view octant's order is the file order's boxes
permuted. compact() keeps each input in the smallest of those forms and the box permutation, and
checks that expand() gives back every array exactly. Needs numpy only."""
import numpy as np

TRIANGLES_PER_BOX = 12


def compact(arrays: dict, period_boxes: int, vertices_per_box: int) -> dict:
    """The preview arrays of gpu_frame_data (input_*, input_names, triangles_file,
    triangles_octant), each input as one period of ``period_boxes`` boxes (period_NAME), one row
    per box (box_NAME) or whole (input_NAME). Raises ValueError where the triangles do not repeat
    so."""
    names = [str(n) for n in arrays["input_names"]]
    vertices = len(arrays["input_pos"])
    boxes = vertices // vertices_per_box
    period = period_boxes * vertices_per_box
    if boxes * vertices_per_box != vertices or boxes % period_boxes:
        raise ValueError(f"{vertices} vertices are not whole periods of {period_boxes} boxes of {vertices_per_box}")
    out = {"input_names": arrays["input_names"], "vertices_per_box": np.int64(vertices_per_box),
           "boxes": np.int64(boxes)}
    for name in names:
        values = arrays[f"input_{name}"]
        if np.array_equal(np.tile(values[:period], (boxes // period_boxes, 1)), values):
            out[f"period_{name}"] = values[:period]
        elif np.array_equal(np.repeat(values[::vertices_per_box], vertices_per_box, axis=0), values):
            out[f"box_{name}"] = values[::vertices_per_box]
        else:
            out[f"input_{name}"] = values
    out["period_triangles"] = arrays["triangles_file"][:period_boxes * TRIANGLES_PER_BOX]
    by_box = np.asarray(arrays["triangles_octant"]).reshape(boxes, TRIANGLES_PER_BOX, 3)
    out["octant_boxes"] = (by_box[:, 0, 0] // vertices_per_box).astype(np.uint32)
    expanded = expand(out)
    if not all(np.array_equal(values, arrays[key]) for key, values in expanded.items()):
        raise ValueError("the chain's triangles do not repeat by periods of two boxes")
    return out


def expand(stored: dict) -> dict:
    """The preview arrays compact() kept, whole again."""
    names = [str(n) for n in stored["input_names"]]
    boxes, per_box = int(stored["boxes"]), int(stored["vertices_per_box"])
    period_triangles = np.asarray(stored["period_triangles"])
    period_boxes = len(period_triangles) // TRIANGLES_PER_BOX
    repeats = boxes // period_boxes
    arrays = {"input_names": stored["input_names"]}
    for name in names:
        if f"period_{name}" in stored:
            arrays[f"input_{name}"] = np.tile(stored[f"period_{name}"], (repeats, 1))
        elif f"box_{name}" in stored:
            arrays[f"input_{name}"] = np.repeat(stored[f"box_{name}"], per_box, axis=0)
        else:
            arrays[f"input_{name}"] = stored[f"input_{name}"]
    offsets = (np.arange(repeats, dtype=np.uint32) * np.uint32(period_boxes * per_box))[:, None, None]
    file_order = (period_triangles[None] + offsets).reshape(-1, 3).astype(np.uint32)
    arrays["triangles_file"] = file_order
    arrays["triangles_octant"] = file_order.reshape(boxes, TRIANGLES_PER_BOX, 3)[stored["octant_boxes"]].reshape(-1, 3)
    return arrays

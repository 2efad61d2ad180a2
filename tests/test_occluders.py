"""The conservative occluders of the hidden-box pre-pass (box_params.glsl bm_occluder_*, through
core.occluder_boxes): every point of every occluder box lies inside its preset's shape (the
preset's own SDF, core.sdf_distance, at most 0) and inside the box the shape is drawn in, for
boxes of every proportion; and they are tight: grown by 2 % of the box they no longer fit."""
import numpy as np
import pytest

from boxmarch import core

GRID = np.stack(np.meshgrid(*[np.linspace(-1.0, 1.0, 7)] * 3, indexing="ij"), -1).reshape(-1, 3)


def half_extents():
    rng = np.random.default_rng(11)
    return np.vstack([rng.uniform(0.05, 1.0, (150, 3)), [[0.23, 0.115, 0.03], [1.0, 1.0, 1.0], [0.1, 1.0, 0.5]]])


def occluder_points(sdf, h, grow=0.0):
    """Grid points of every occluder box (grown by ``grow`` x the box's largest half-extent), with
    the half-extents of their box."""
    centres, halves = core.occluder_boxes(sdf, h)
    points, boxes = [], []
    for i in range(len(h)):
        for centre, extent in zip(centres[i], halves[i]):
            if extent.min() <= 0.0:
                continue
            points.append(centre + GRID * (extent + grow * h[i].max()))
            boxes.append(np.tile(h[i], (len(GRID), 1)))
    return np.concatenate(points), np.concatenate(boxes)


@pytest.mark.parametrize("sdf", core.SDF_PRESETS)
def test_occluders_lie_inside_the_shape_and_its_box(sdf):
    h = half_extents()
    points, boxes = occluder_points(sdf, h)
    assert len(points) >= len(h) * len(GRID)  # at least one occluder per box
    assert np.all(np.abs(points) <= boxes)
    assert core.sdf_distance(sdf, points, boxes).max() <= 0.0


@pytest.mark.parametrize("sdf", core.SDF_PRESETS)
def test_occluders_grown_by_two_percent_leave_the_shape(sdf):
    # negative control: the check above can fail, and the occluders are as large as stated
    h = half_extents()
    points, boxes = occluder_points(sdf, h, grow=0.02)
    outside = (core.sdf_distance(sdf, points, boxes) > 0.0) | np.any(np.abs(points) > boxes, axis=1)
    assert outside.any()


def test_occluder_counts_per_preset():
    counts = {sdf: int((core.occluder_boxes(sdf, [0.5, 0.4, 0.3])[1][0].min(axis=1) > 0).sum())
              for sdf in core.SDF_PRESETS}
    assert counts == {"BOX": 1, "SPHERE": 3, "ROUNDED_BOX": 3, "CAPSULE": 2, "CYLINDER": 2, "TORUS": 4, "LINK": 4}

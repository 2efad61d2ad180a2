"""mesh_data.layers_over_view, which decides whether an object marches in the preview's resolved
passes (preview/resolve.py: from resolve.MIN_OVERDRAW layers): checked against layouts whose
projected areas are known from the camera's geometry alone."""
import numpy as np
import pytest

from boxmarch.preview import mesh_data
from tests.engines import perspective


def test_boxes_ahead_count_their_projected_discs():
    # a 90-degree view 400 px high: at distance 10 the view is 20 units high, 20 px per unit
    projection = perspective({"fov": 90.0, "near": 0.1, "far": 100.0}, 1.0)
    half = np.full((5, 3), 0.5)
    radius = np.sqrt(3) * 0.5
    origins = np.array([[0.0, 0.0, -10.0]] * 5)
    expected = 5 * np.pi * (radius * 20.0) ** 2 / (400 * 400)
    assert mesh_data.layers_over_view(origins, half, projection, 400, 400) == pytest.approx(expected, rel=1e-9)


def test_boxes_behind_the_eye_or_outside_the_view_count_nothing():
    projection = perspective({"fov": 90.0, "near": 0.1, "far": 100.0}, 1.0)
    half = np.full((3, 3), 0.5)
    origins = np.array([[0.0, 0.0, 10.0], [30.0, 0.0, -10.0], [0.0, -30.0, -10.0]])
    assert mesh_data.layers_over_view(origins, half, projection, 400, 400) == 0.0


def test_a_box_filling_the_view_counts_one_layer():
    projection = perspective({"fov": 90.0, "near": 0.1, "far": 100.0}, 1.0)
    assert mesh_data.layers_over_view(np.array([[0.0, 0.0, -1.0]]), np.full((1, 3), 5.0), projection, 400, 300) == 1.0


def test_the_object_matrix_is_applied():
    """The same boxes moved by an object matrix: the layers follow the boxes as drawn."""
    projection = perspective({"fov": 60.0, "near": 0.1, "far": 100.0}, 1.5)
    origins = np.array([[0.0, 0.0, 0.0], [0.3, 0.2, 0.1]])
    half = np.full((2, 3), 0.2)
    model = np.eye(4)
    model[:3, 3] = (0.0, 0.0, -4.0)
    moved = origins + model[:3, 3]
    assert mesh_data.layers_over_view(origins, half, projection @ model, 300, 200) == pytest.approx(
        mesh_data.layers_over_view(moved, half, projection, 300, 200))
    assert mesh_data.layers_over_view(origins, half, projection, 300, 200) == 0.0  # at or behind the eye (w <= 0)

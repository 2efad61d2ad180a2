"""Pieces that do not look like boxes (core.not_boxes) and the bake's warning about them: a modelled
torus baked as it is draws clipped to its own faces, so the bake says to model one box per shape;
boxes, with their faces cut into grids or not, get no warning."""
import numpy as np

from boxmarch import core, scenes
from tests.conftest import mesh_object


def quad_mesh(quads):
    """Mesh arrays (positions, edges, face_starts, face_sizes, corner_verts) of quads given by their
    corner positions (F, 4, 3), corners at the same place (to 1e-6) welded into one vertex."""
    corners = np.asarray(quads, np.float64).reshape(-1, 3)
    _unique, first, corner_verts = np.unique(np.round(corners, 6), axis=0, return_index=True, return_inverse=True)
    corner_verts = corner_verts.reshape(-1)
    faces = corner_verts.reshape(-1, 4)
    edges = np.unique(np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], 2).reshape(-1, 2), axis=1), axis=0)
    return (corners[first].astype(np.float32), edges.astype(np.int32), np.arange(0, 4 * len(faces), 4, dtype=np.int32),
            np.full(len(faces), 4, np.int32), corner_verts.astype(np.int32))


def torus_quads(major=1.0, minor=0.25, around=32, tube=12):
    u = 2 * np.pi * np.arange(around + 1) / around
    v = 2 * np.pi * np.arange(tube + 1) / tube
    uu, vv = np.meshgrid(u, v, indexing="ij")
    points = np.stack([(major + minor * np.cos(vv)) * np.cos(uu), (major + minor * np.cos(vv)) * np.sin(uu),
                       minor * np.sin(vv)], axis=2)
    return np.stack([points[:-1, :-1], points[1:, :-1], points[1:, 1:], points[:-1, 1:]], axis=2).reshape(-1, 4, 3)


def grid_box_quads(size, cuts=3):
    """A box of ``size`` whose every face is a cuts x cuts grid of quads (as Blender's Subdivide leaves it)."""
    s = np.linspace(-0.5, 0.5, cuts + 1)
    quads = []
    for axis in range(3):
        for side in (-0.5, 0.5):
            a, b = [k for k in range(3) if k != axis]
            for i in range(cuts):
                for j in range(cuts):
                    quad = np.zeros((4, 3))
                    quad[:, axis] = side
                    quad[:, a] = [s[i], s[i + 1], s[i + 1], s[i]]
                    quad[:, b] = [s[j], s[j], s[j + 1], s[j + 1]]
                    quads.append(quad * size)
    return np.array(quads)


def turned(quads, rotation, centre):
    return np.asarray(quads) @ np.asarray(rotation).T + centre


def test_a_torus_is_not_a_box_and_grid_boxes_are():
    rotations = scenes.random_rotations(3, np.random.default_rng(7))
    quads = np.concatenate([turned(grid_box_quads([1.0, 0.5, 0.12]), rotations[0], [0, 0, 0]),
                            turned(torus_quads(), rotations[1], [5, 0, 0]),
                            turned(grid_box_quads([2.0, 2.0, 2.0], cuts=5), rotations[2], [0, 5, 0])])
    arrays = quad_mesh(quads)
    result = core.bake(*arrays)
    not_box, off_box = core.not_boxes(arrays[0], result.submesh_of_vertex, result.quaternions)
    torus = result.submesh_of_vertex[np.argmax(np.linalg.norm(arrays[0] - [5, 0, 0], axis=1) < 2)]
    assert np.flatnonzero(not_box).tolist() == [torus]
    assert off_box[torus] > 0.5  # most of a torus lies inside its bounding box
    assert np.all(np.delete(off_box, torus) == 0.0)


def test_boxes_of_eight_vertices_are_never_reported():
    arrays, _centres, _sizes, _rotations = scenes.random_boxes(200, seed=3)
    result = core.bake(*arrays)
    not_box, off_box = core.not_boxes(arrays[0], result.submesh_of_vertex, result.quaternions)
    assert not not_box.any() and not off_box.any()


def test_the_bake_warns_about_a_modelled_torus_and_not_about_boxes(blender, capfd):
    from boxmarch import bake_job, mesh_io

    bpy = blender
    boxes = mesh_object(bpy, "Boxes", *scenes.random_boxes(20, seed=1)[0])
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    assert "do not look like boxes" not in capfd.readouterr().out
    boxes.select_set(False)
    quads = np.concatenate([torus_quads(), turned(torus_quads(), np.eye(3), [4, 0, 0]), grid_box_quads([1, 1, 1]) + 9])
    torus = mesh_object(bpy, "Tori", *quad_mesh(quads))
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}  # baked, with a WARNING report
    out = capfd.readouterr().out
    assert "mesh 'Tori': 2 of its 3 pieces do not look like boxes (piece" in out, out
    assert "model one box per shape" in out
    (prepared,) = bake_job.bake_meshes([torus.data], mesh_io.BakeSettings(incremental=False))
    (warning,) = bake_job.not_box_warnings([prepared.report])
    assert "384 vertices" in warning  # 32 x 12 around the tube
    assert bake_job.not_box_warnings(
        [p.report for p in bake_job.bake_meshes([boxes.data], mesh_io.BakeSettings(incremental=False))]) == []


def test_the_warning_reads_well_for_one_piece_or_many():
    """Singular and plural agree with the counts, and the line stays short: the warning once read
    "1 of its 1 pieces do not look like boxes" on a line of 250 characters."""
    from boxmarch import bake_job

    example = {"submesh": 4, "vertices": 384, "off_box": 0.67}
    cases = {(1, 1): "mesh 'Torus' does not look like a box (384 vertices, 67% off its faces)",
             (3, 3): "mesh 'Torus': its 3 pieces do not look like boxes (piece 4: 384 vertices, 67% off its faces)",
             (1, 3): "mesh 'Torus': 1 of its 3 pieces does not look like a box (piece 4: 384 vertices",
             (2, 1000): "mesh 'Torus': 2 of its 1,000 pieces do not look like boxes (piece 4: 384 vertices"}
    for (found, pieces), start in cases.items():
        (warning,) = bake_job.not_box_warnings([{"mesh": "Torus", "not_boxes": found, "submeshes": pieces,
                                                 "not_box_example": example}])
        assert warning.startswith(start), warning
        assert warning.endswith(": model one box per shape, not the shape (docs/PREVIEW.md)"), warning
        assert len(warning) <= 160, (len(warning), warning)
    assert bake_job.not_box_warnings([{"mesh": "Boxes", "not_boxes": 0, "submeshes": 5, "not_box_example": None}]) == []

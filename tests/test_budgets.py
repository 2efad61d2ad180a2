"""The triangle budget table (bench/bench_budgets.py, docs/BENCHMARKS.md *Triangle budgets*): its
triangle counts are those of exported files, counted by the tests' own glTF reader
(tests/helpers/file_vertices.py), and its ranks follow VRChat's published limits."""
import numpy as np

from bench.bench_boxes_vs_triangles import chain_mesh, chain_rows
from bench.bench_boxes_vs_triangles import link_mesh
from bench.bench_budgets import budget_rows, equal_error_per_link, rank
from boxmarch import mesh_io, scenes
from tests.conftest import mesh_object
from tests.helpers.file_vertices import glb_counts

LINKS = 100
LEVEL = (6, 3)  # any tessellation: the table multiplies, the file counts


def test_budget_table_triangles_are_those_of_exported_files(blender, tmp_path):
    bpy = blender
    per_link = len(link_mesh(*LEVEL)[2])
    rows = {method: triangles for _links, method, triangles, _pc, _quest in budget_rows({"mesh": per_link}, (LINKS,))}
    scene = chain_rows(LINKS)
    origins, rotations, half = scene[:3]
    mesh_object(bpy, "Boxes", *scenes.box_arrays(origins, 2 * half, rotations))
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    boxes_path = tmp_path / "boxes.glb"
    assert bpy.ops.boxmarch.export(filepath=str(boxes_path), preset="GLTF") == {"FINISHED"}

    bpy.ops.object.select_all(action="DESELECT")
    positions, _normals, triangles = chain_mesh(scene, *LEVEL)
    mesh = mesh_io.new_mesh("Links", positions, np.arange(0, 3 * len(triangles), 3), np.full(len(triangles), 3),
                            triangles.reshape(-1))
    ob = bpy.data.objects.new("Links", mesh)
    bpy.context.scene.collection.objects.link(ob)
    ob.select_set(True)
    mesh_path = tmp_path / "links.glb"
    assert bpy.ops.export_scene.gltf(filepath=str(mesh_path), export_format="GLB", use_selection=True) == {"FINISHED"}

    assert glb_counts(boxes_path)["triangles"] == rows["boxes"]
    assert glb_counts(mesh_path)["triangles"] == rows["mesh"]


def test_ranks_follow_vrchat_limits():
    """VRChat's published Polygons maximums (bench_budgets.VRCHAT_TRIANGLE_LIMITS cites them):
    PC Excellent 32,000, Good 70,000 (Medium and Poor allow no more); Quest 7,500, 10,000,
    15,000, 20,000."""
    assert [rank("PC", t) for t in (32_000, 32_001, 70_000, 70_001)] == ["Excellent", "Good", "Good", "Very Poor"]
    assert [rank("Quest", t) for t in (7_500, 7_501, 10_001, 15_001, 20_000, 20_001)] == \
        ["Excellent", "Good", "Medium", "Poor", "Poor", "Very Poor"]


def test_equal_error_mesh_is_the_coarsest_at_the_boxes_error():
    """From curve points: 10 links (120 box triangles), boxes 0.2 %; meshes of 40, 80 and 160
    triangles a link at 0.5, 0.15 and 0.1 %: 80 a link, reached; with the boxes at 0.01 % none
    reaches it: the finest, 160, marked; the boxes' 512-step point (0.12 %), asked for: 160, reached."""
    def points(boxes_coverage):
        return ([{"renderer": "r", "scene": "close chain", "method": "boxes", "setting": "defaults (LINK)",
                  "triangles": 120, "coverage": boxes_coverage},
                 {"renderer": "r", "scene": "close chain", "method": "boxes", "setting": "512 steps, 1e-6",
                  "triangles": 120, "coverage": 0.12},
                 {"renderer": "r", "scene": "other", "method": "boxes", "setting": "defaults", "triangles": 12,
                  "coverage": 9.0}]
                + [{"renderer": "r", "scene": "close chain", "method": "mesh", "setting": "", "triangles": 10 * t,
                    "coverage": c} for t, c in ((160, 0.1), (40, 0.5), (80, 0.15))])
    assert equal_error_per_link(points(0.2), "r") == (80, True, 0.2)
    assert equal_error_per_link(points(0.01), "r") == (160, False, 0.01)
    assert equal_error_per_link(points(0.2), "r", setting="512 steps") == (160, True, 0.12)

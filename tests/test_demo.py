"""The demo shows what boxmarch is for (issue 37): a posed character wearing chains of links.
The demo runs here (100 pebbles, the CPU preview); its character must be posed as
demo_character.POSE says, checked against this file's own forward kinematics of the rest boxes
(each bone turned about its rest head, carrying its children); and three.js, posing demo.glb's
bones as scripts/threejs_picture.py does, must draw every link where that kinematics puts it,
within 1 px (the links drawn as their whole boxes, the other meshes hidden). Negative controls:
the rest boxes miss the posed mesh, and the unposed page misses the posed silhouettes."""
import math

import numpy as np
import pytest

from boxmarch import demo_character
from tests.engine_scene import TO_Y_UP, axis_turn, silhouettes
from tests.engines import coverage_mismatch, threejs
from tests.helpers.tools import need

pytestmark = [pytest.mark.slow, pytest.mark.bpy]  # the demo in bpy, then three.js in Chromium


@pytest.fixture(scope="module")
def demo_scene(bpy_module, tmp_path_factory):
    from boxmarch import demo

    folder = tmp_path_factory.mktemp("demo")
    _rows, report = demo.run_demo(100, 1, str(folder), "CPU", lambda _message: None)
    return bpy_module, folder, report


def bone_motions():
    """{bone: 4 x 4 world motion from rest to the pose}: forward kinematics of BONES under POSE."""
    motions = {}
    for name, (head, _tail, parent) in demo_character.BONES.items():
        turn = np.eye(4)
        if name in demo_character.POSE:
            axis, degrees = demo_character.POSE[name]
            turn[:3, :3] = axis_turn(axis, math.radians(degrees))
            turn[:3, 3] = np.asarray(head) - turn[:3, :3] @ head
        motions[name] = (motions[parent] if parent else np.eye(4)) @ turn
    return motions


def posed_links():
    """(centres, rotations, sizes) of the chain links carried rigidly by their bones."""
    centres, rotations, sizes, bones = demo_character.links()
    motion = np.array([bone_motions()[bone] for bone in bones])
    return (np.einsum("nij,nj->ni", motion[:, :3, :3], centres) + motion[:, :3, 3],
            np.einsum("nij,njk->nik", motion[:, :3, :3], rotations), sizes)


def test_blender_poses_the_character_as_the_pose_says(demo_scene):
    bpy, _folder, report = demo_scene
    rig, chains = bpy.data.objects["Rig"], bpy.data.objects["Chains"]
    assert len(rig.data.bones) == report["bones"] > 1 and len(demo_character.POSE) > 1
    for name in demo_character.POSE:
        rest, posed = np.array(rig.data.bones[name].matrix_local), np.array(rig.pose.bones[name].matrix)
        assert np.abs(rest[:3, :3] - posed[:3, :3]).max() > 0.05, name  # the bone is turned
    bpy.context.view_layer.update()
    evaluated = chains.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    shown = np.array([v.co[:] for v in evaluated.vertices]).reshape(-1, 8, 3).mean(axis=1)
    centres, _rotations, _sizes = posed_links()
    assert len(shown) == report["links"] == len(centres)
    assert np.abs(shown - centres).max() < 1e-4
    # Control: the rest links are far from the posed mesh (the arms' chains moved most).
    assert np.abs(shown - demo_character.links()[0]).max() > 1.0


def test_threejs_draws_each_link_where_the_pose_puts_it(demo_scene):
    need(threejs.available())
    from scripts import threejs_picture

    _bpy, folder, _report = demo_scene
    width, height = 400, 300  # the picture's aspect, smaller
    whole_boxes = threejs_picture.materials_js({"Chains": ("BOX", (1.0, 1.0, 1.0))})
    jobs = [threejs.render_job(setup, width, height, threejs_picture.CAMERA)
            for setup in (threejs_picture.pose_js() + whole_boxes, whole_boxes)]
    material = threejs.shipped_material()
    posed, unposed = threejs.run_jobs((folder / "demo.glb").read_bytes(), jobs, material)
    centres, rotations, sizes = posed_links()
    expected = silhouettes(posed, centres, sizes, rotations, TO_Y_UP)
    assert posed.pixels[..., 3].astype(bool).mean() > 0.02  # the chains fill a fair part of the view
    mismatch = coverage_mismatch(posed.pixels[..., 3] > 0, expected)
    assert mismatch is None, mismatch
    assert coverage_mismatch(unposed.pixels[..., 3] > 0, expected) is not None


def test_idea_picture_prints_its_one_line_alone(tmp_path):
    """scripts/idea_picture.py (README's picture) says what it wrote and nothing else: no bake
    report, no EGL_BAD_MATCH lines of Blender's first GPU context, no glTF exporter progress."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import boxmarch
    from tests.helpers.blender_program import python_env

    need(threejs.available())
    root = Path(__file__).resolve().parent.parent
    env = python_env(dict(os.environ), Path(boxmarch.__file__).parent.parent, root)
    proc = subprocess.run([sys.executable, "-m", "scripts.idea_picture", "--out", "pictures"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    printed = (proc.stdout + proc.stderr).splitlines()
    assert len(printed) == 1 and printed[0].startswith("idea_picture: wrote") and len(printed[0]) <= 100, printed
    assert (tmp_path / "pictures" / "idea.png").stat().st_size > 0

"""Skinning figures (issue 13): how close a skinned NORMAL_FRAME export lands when posed, and what
a box whose vertices carry different bone weights costs.

Rigid rig (tests/engine_scene.py: 3 bones, 36 boxes each weighted 1.0 to its bone, 40 degrees at
each joint), exported with the GLTF preset:
* three.js r111 (WebGL 1) and r180 (WebGL 2), headless Chromium, SwiftShader: the tightest
  tolerance in px at which the shipped material's boxes at 0.6 of each half-extent cover the
  posed silhouettes of the test's forward kinematics (the tests require 1 px), and the same for the rest-frame negative control;
* Godot 3.2 (godot3 under xvfb-run, llvmpipe): the GODOT3 preset's export imported with
  compression off, posed by Skeleton.set_bone_pose, the shipped shader: the same figure, and its
  rest-frame negative control;
* the .glb skinned in NumPy with the glTF formula, and the UNITY preset's FBX through the modelled
  Unity import and skinning (engine_scene.unity_skinned_decode): worst decoded origin error /
  largest half-extent, axis error (1 - cos), half-extent error, against the posed boxes, with
  the skinned frame and with the frame left at rest.

Non-rigid boxes (NumPy, the shader's decode): a 1 x 0.6 x 0.2 box straddling a joint, its long
axis along the bone; the joint turns 40 degrees. Its vertices at one end carry weight w - s/2 on
the turning bone, at the other w + s/2 (s: the spread). The error is the worst, over its
vertices, of |decoded origin - the box centre carried by the box's mean weights| over the
largest half-extent (the shader normalises the skinned axes; y = cross(z, x)).

    PYTHONPATH=addon python3 -m bench.bench_skinning            # the table
    PYTHONPATH=addon python3 -m bench.bench_skinning --no-engine  # non-rigid table only (no Blender)
"""
import argparse
import os
import pathlib
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from bench.common import table  # noqa: E402
from tests.engine_scene import axis_turn  # noqa: E402

BOX_HALF = np.array([0.5, 0.3, 0.1])
TURN = np.radians(40.0)
SPREADS = np.round(np.arange(0.0, 0.501, 0.05), 2)
# Where the box's mean weight on the turning bone sits: a blend centred on the joint, and one
# end on the bone with the other end slipping off it.
MEAN_WEIGHTS = {"0.5 - s/2 .. 0.5 + s/2": lambda s: 0.5, "1 - s .. 1": lambda s: 1.0 - s / 2}


def nonrigid_error(spread, mean_weight, angle=TURN):
    """Worst decoded-origin error / largest half-extent of the straddling box (module docstring)."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    rest = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T  # local x along the bone (z)
    rest = rest @ axis_turn([1.0, 0.3, 0.2], 0.25)                          # and a little off it
    centre = np.array([0.0, 0.0, 0.1])                                       # the joint at the origin
    positions = centre + (corners * BOX_HALF) @ rest.T
    offsets = -(corners * BOX_HALF)                                          # f: vertex to centre, box-local
    weights = mean_weight + spread / 2 * corners[:, 0]                       # on the turning bone, by end
    turn = axis_turn([1.0, 0.0, 0.0], angle)
    blend = (1.0 - weights)[:, None, None] * np.eye(3) + weights[:, None, None] * turn  # joint at the origin
    skinned = np.einsum("nij,nj->ni", blend, positions)
    unit = lambda v: v / np.linalg.norm(v, axis=1, keepdims=True)
    x = unit(np.einsum("nij,j->ni", blend, rest[:, 0]))
    z = unit(np.einsum("nij,j->ni", blend, rest[:, 2]))
    y = unit(np.cross(z, x))
    origins = skinned + x * offsets[:, :1] + y * offsets[:, 1:2] + z * offsets[:, 2:]
    mean = weights.mean()
    expected = ((1.0 - mean) * np.eye(3) + mean * turn) @ centre
    return float(np.linalg.norm(origins - expected, axis=1).max() / BOX_HALF.max())


def nonrigid_rows():
    return [[f"{s:.2f}"] + [f"{nonrigid_error(s, mean(s)):.1e}" for mean in MEAN_WEIGHTS.values()] for s in SPREADS]


def nonrigid_table():
    return table(["weight spread s"] + [f"weights {name}" for name in MEAN_WEIGHTS], nonrigid_rows())


def accuracy_section():
    """The Skinning section of docs/ACCURACY.md (bench_accuracy.py writes the page with it)."""
    return f"""
## Skinning: boxes whose vertices carry different bone weights

A box decodes exactly when skinning moves it rigidly: every vertex on one bone (or on the same
weights of the same bones, and then only if the blend of those bones' matrices is a rotation).
Measured on the rig of the skinning tests (3 bones, 36 boxes each weighted 1.0 to its bone, 40
degrees at each joint): 1.1e-06 of the half-extent after the glTF round trip skinned in NumPy,
within 1 px in three.js r111 and r180 (docs/ENGINES.md, Skinning).

When a box's vertices carry different weights, each vertex's skinned frame differs, and the
decoded origins leave the box: the shape tears and shifts. `bench/bench_skinning.py` measures a
1 x 0.6 x 0.2 box straddling a joint, long axis along the bone, the joint turned 40 degrees; the
vertices at one end carry weight w - s/2 on the turning bone, at the other end w + s/2 (s: the
weight spread). Error: worst over the vertices of |decoded origin - the box centre moved by the
box's mean weights| / largest half-extent, decoding as the shipped shaders do (skinned axes
normalised, y = cross(z, x)).

{nonrigid_table()}

![Decode error against the weight spread inside a box](accuracy_skinning.png)

(`scripts/skinning_accuracy_plot.py` draws the plot.) Even at s = 0 a box blended half and half
between two bones is off by 7 % of its half-extent: linear blend skinning's matrix
(1 - w) A + w B is no rotation, so the skinned axes are skewed and shortened. With one end fully
on the bone (the second column) the error grows about linearly, 0.3 % of the half-extent per
0.01 of spread at first. Weight each box to one bone (the export report counts the boxes that are
not, `non_rigid_boxes`, and warns).
"""



def engine_rows():
    import bpy

    import boxmarch
    from boxmarch.export import scene as export_scene
    from tests.engine_scene import (TO_Y_UP, UNITY, box_of_vertex, decode_normal_frame, frame_and_size_errors,
                                    posed_rig_boxes, rig_boxes, skinned_scene, unity_skinned_decode)
    from tests.fbx_reader import read_fbx_geometry, read_fbx_skin
    from tests import test_engine_skinned as skinned_test
    from tests.engines import godot3, threejs, tightest_tolerance

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ob, _rig = skinned_scene(bpy)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "skinned.glb"
        start = time.perf_counter()
        export_scene.export_objects(bpy.context, [ob], "GLTF", str(path))
        export_s = time.perf_counter() - start
        p, positions, normals, tangents = skinned_test.gltf_pose_skinning(path)
        centres, sizes, rotations, _bones = rig_boxes()
        box = box_of_vertex(p["POSITION"], centres, sizes, rotations, TO_Y_UP)
        offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
        half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
        posed_centres, posed_rotations = posed_rig_boxes()
        for name, n, t in (("skinned frame", normals, tangents), ("rest frame", p["NORMAL"], p["TANGENT"])):
            decoded = decode_normal_frame(positions, n, t, offset, half)
            errors = frame_and_size_errors(*decoded, box, posed_centres, sizes, posed_rotations, TO_Y_UP)
            rows.append([f"glTF skinned in NumPy, {name}", *(f"{e:.1e}" for e in errors), "-", f"{export_s:.2f}"])
        fbx_path = os.path.join(folder, "skinned.fbx")
        start = time.perf_counter()
        export_scene.export_objects(bpy.context, [ob], "UNITY", fbx_path)
        export_s = time.perf_counter() - start
        raw, skin = read_fbx_geometry(fbx_path), read_fbx_skin(fbx_path)
        fbx_box = box_of_vertex(raw["position"] @ UNITY["from_file"].T, centres, sizes, rotations, UNITY["to_engine"])
        for name, decoded in zip(("skinned frame", "rest frame"), unity_skinned_decode(raw, skin)):
            errors = frame_and_size_errors(*decoded, fbx_box, posed_centres, sizes, posed_rotations, UNITY["to_engine"])
            rows.append([f"Unity FBX (modelled import), {name}", *(f"{e:.1e}" for e in errors), "-", f"{export_s:.2f}"])
        views = [(f"{name}, {camera_name}", tamper, camera)
                 for name, tamper in (("shipped material", None), ("rest frame (negative control)", skinned_test.REST_FRAME))
                 for camera_name, camera in (("side", skinned_test.SIDE), ("top", skinned_test.TOP))]
        for release, spec in threejs.RELEASES.items():
            if threejs.available(release):
                continue
            start = time.perf_counter()
            jobs = [threejs.render_job(skinned_test.setup_js(tamper), skinned_test.W, skinned_test.H, camera)
                    for _name, tamper, camera in views]
            shots = threejs.run_jobs(path.read_bytes(), jobs, threejs.shipped_material(release), release)
            seconds = (time.perf_counter() - start) / len(views)
            for (name, _tamper, _camera), shot in zip(views, shots):
                tol = tightest_tolerance(skinned_test.covered(shot), skinned_test.posed_silhouettes(shot))
                rows.append([f"three.js r{spec.revision} ({spec.context}), {name}", "-", "-", "-", tol,
                             f"{seconds:.1f} (one page)"])
        start = time.perf_counter()
        os.makedirs(os.path.join(folder, "godot3"))
        project = skinned_test.godot3_import_skinned(bpy.context, ob, os.path.join(folder, "godot3"))
        import_s = time.perf_counter() - start
        for name, frame in (("shipped shader", None), ("rest frame (negative control)", godot3.REST_FRAME)):
            start = time.perf_counter()
            shot, covered = skinned_test.godot3_posed_shot(project, frame)
            seconds = time.perf_counter() - start
            tol = tightest_tolerance(covered, skinned_test.posed_silhouettes(shot))
            rows.append([f"Godot 3.2 (GODOT3, Compress off), {name}, side", "-", "-", "-", tol,
                         f"{seconds:.1f} (+{import_s:.1f} import)"])
    return table(["check", "origin", "axis", "half", "render px", "s"], rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--no-engine", action="store_true", help="only the non-rigid table (no Blender, no Chromium)")
    args = parser.parse_args()
    if not args.no_engine:
        print("Rigid rig, 36 boxes, 40 degrees per joint:\n")
        print(engine_rows())
        print()
    print("Non-rigid box, 40 degree turn, decode error / largest half-extent:\n")
    print(nonrigid_table())


if __name__ == "__main__":
    main()

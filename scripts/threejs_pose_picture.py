"""Writes docs/threejs_pose.png: the chain of scripts/chain_arm.py (a few hundred links wound around
a 3-bone arm, each rigidly weighted to the bone under it) exported with the GLTF preset
(NORMAL_FRAME, skinned), loaded unmodified by three.js r111's GLTFLoader in headless Chromium,
the arm bent 40 degrees at each joint in the page, raymarched by the shipped ShaderMaterial
(skinning: true). Left: as shipped, every link stays in its box. Right: the frame left at rest,
as a layout with the frame in UV maps gives it: the links slide out of their boxes. Seen as
docs/preview_pose.png sees the same arm in Blender's preview.

Usage: PYTHONPATH=addon python3 -m scripts.threejs_pose_picture [OUT.png]
"""
import math
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
import bpy  # noqa: E402

import boxmarch  # noqa: E402
from scripts import chain_arm  # noqa: E402
from boxmarch import mesh_io  # noqa: E402
from boxmarch.export import scene as export_scene  # noqa: E402
from tests.engines import threejs  # noqa: E402
from scripts.threejs_picture import write_png  # noqa: E402

W, H = 640, 540
TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # Blender -> glTF axes
LINK_MAP = "return sdf_preset_link(p, box_half);"
# The frame as the vertex carries it at rest (no skinning), in place of the skinned one.
REST_FRAME = ("bmObjPos = transformed;", "objectNormal = normal; axisX = tangent.xyz; bmObjPos = transformed;")


def setup_js(rest_frame):
    tamper = ""
    if rest_frame:
        old, new = REST_FRAME
        tamper = f"m.vertexShader = m.vertexShader.replace({old!r}, {new!r});"
    turns = {f"bone{k}": TO_Y_UP @ [1.0, 0.0, 0.0] for k in range(3)}
    return (threejs.pose_bones_js(turns, chain_arm.BONE_TURN)
            + "gltf.scene.traverse(function (o) { if (!o.isSkinnedMesh) return; o.frustumCulled = false;"
            + f" var m = createBoxmarchMaterial(THREE, {{map: {LINK_MAP!r}, color: new THREE.Color(0.85, 0.65, 0.3),"
            + " maxSteps: 96, skinning: true});" + tamper + " useBoxmarchMaterial(THREE, o, m); });")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "threejs_pose.png")
    reason = threejs.available()
    if reason:
        print(f"threejs_pose_picture: skipped, {reason}")
        return 0
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    chain, rig, links = chain_arm.build(bpy, scene)
    chain_arm.pose(rig)  # posed in Blender only to frame the camera: the file holds the rest pose
    bpy.context.view_layer.update()
    posed = mesh_io.read_positions(chain.evaluated_get(bpy.context.evaluated_depsgraph_get()).data) @ TO_Y_UP.T
    low, high = posed.min(axis=0), posed.max(axis=0)
    target = (low + high) / 2  # seen as scripts/preview_pose_picture.py sees it, in glTF's axes
    position = target + TO_Y_UP @ np.array([1.0, -0.25, 0.15]) * 1.25 * float(np.linalg.norm(high - low))
    camera = {"position": position.tolist(), "target": target.tolist(), "near": 0.5, "far": 100.0,
              "fov": math.degrees(2 * math.atan(18.0 / 40.0 * H / W))}  # 40 mm lens, 36 mm sensor width
    material = open(os.path.join(ROOT, "shaders", "threejs", "boxmarch.js")).read()
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "chain.glb")
        report = export_scene.export_objects(bpy.context, [chain], "GLTF", path)
        glb = open(path, "rb").read()
    start = time.perf_counter()
    panels = [threejs.render(glb, material, setup_js(rest), W, H, camera).pixels for rest in (False, True)]
    gap = np.zeros((H, 4, 4), np.uint8)
    gap[..., :3], gap[..., 3] = 128, 255
    write_png(out, np.concatenate([panels[0], gap, panels[1]], axis=1))
    print(f"threejs_pose_picture: wrote {out} ({links} links, {report['layout']}, bones "
          f"{', '.join(report['skinned']['chain']['bones'])}; {time.perf_counter() - start:.1f} s in three.js)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Writes docs/idea.png, the picture of what boxmarch is for. Left: what the artist models in
Blender, one thin box per chain link wound around a 3-bone arm (the arm's flesh a skinned
cylinder), posed, as Blender's Workbench renders the meshes. Right: the same box mesh, baked with
every default and exported with the GLTF preset's defaults, loaded unmodified by three.js r111 in
headless Chromium, posed by the same bones and raymarched by the shipped material: every box a
chain link (sdf_preset_link), one draw call; the flesh drawn by three.js as a capsule per bone.

Usage: .venv-demo/bin/python -m scripts.idea_picture [--out FOLDER]   (writes FOLDER/idea.png; default docs/)
About 25 s on a 2-core machine (most of it three.js on SwiftShader); skipped, with a line saying why,
where Chromium or three.js r111 is missing.
"""
import argparse
import math
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
import bpy  # noqa: E402
import mathutils  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import blender_output  # noqa: E402
from boxmarch.export import scene as export_scene  # noqa: E402
from scripts import chain_arm  # noqa: E402
from scripts.threejs_picture import write_png  # noqa: E402
from tests.engines import threejs  # noqa: E402

W, H = 600, 420
TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # Blender -> glTF axes
# Fewer, larger links than the posed pictures' chain: each link tens of pixels long here.
LINK = np.array([0.9, 0.45, 0.11])
RADIUS, TURNS, FLESH = 0.85, 7, 0.55  # helix radius and turns; the arm's own radius inside it
GOLD, FLESH_COLOUR = (0.85, 0.65, 0.3), (0.55, 0.6, 0.68)


def flesh(scene, rig):
    """A cylinder of radius FLESH up the arm (z 0..ARM), skinned to the three bones with weights
    blended over 0.6 around each joint, so it bends as an arm does."""
    around, rings = 32, 46
    angle = 2 * np.pi * np.arange(around) / around
    z = np.linspace(0.0, chain_arm.ARM, rings)
    positions = np.stack([np.tile(FLESH * np.cos(angle), rings), np.tile(FLESH * np.sin(angle), rings),
                          np.repeat(z, around)], axis=1)
    a = np.arange(around)
    quads = [[r * around + a[i], r * around + a[(i + 1) % around], (r + 1) * around + a[(i + 1) % around],
              (r + 1) * around + a[i]] for r in range(rings - 1) for i in range(around)]
    mesh = bpy.data.meshes.new("flesh")
    mesh.from_pydata(positions.tolist(), [], quads)
    ob = bpy.data.objects.new("flesh", mesh)
    scene.collection.objects.link(ob)
    ob.color = (*FLESH_COLOUR, 1.0)
    third = chain_arm.ARM / 3
    for k in range(3):
        low = np.clip((positions[:, 2] - (k * third - 0.3)) / 0.6, 0.0, 1.0) if k else np.ones(len(positions))
        high = np.clip(((k + 1) * third + 0.3 - positions[:, 2]) / 0.6, 0.0, 1.0) if k < 2 else np.ones(len(positions))
        weight = np.minimum(low, high)
        group = ob.vertex_groups.new(name=f"bone{k}")
        for v in np.flatnonzero(weight > 0):
            group.add([int(v)], float(weight[v]), "REPLACE")
    ob.modifiers.new("Armature", "ARMATURE").object = rig
    return ob


def workbench_panel(scene, path):
    """The posed meshes as Blender's Workbench renders them (object colours, studio light), W x H,
    transparent background: (H, W, 4) uint8, row 0 at the top."""
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.color_type = "OBJECT"
    scene.display.shading.show_object_outline = True
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
    scene.render.film_transparent = True
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.empty(W * H * 4, np.float32)
    image.pixels.foreach_get(pixels)
    return (np.clip(pixels.reshape(H, W, 4)[::-1], 0.0, 1.0) * 255).round().astype(np.uint8)


def setup_js():
    """Poses the bones as chain_arm.pose does, gives the chain the shipped material drawing links,
    and puts a capsule of radius FLESH on each bone (a bone's local y runs along it)."""
    turns = {f"bone{k}": TO_Y_UP @ [1.0, 0.0, 0.0] for k in range(3)}
    third = chain_arm.ARM / 3
    return (threejs.pose_bones_js(turns, chain_arm.BONE_TURN)
            + "gltf.scene.traverse(function (o) { if (!o.isSkinnedMesh) return; o.frustumCulled = false;"
            + " useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {map: 'return sdf_preset_link(p, box_half);',"
            + f" color: new THREE.Color({GOLD[0]}, {GOLD[1]}, {GOLD[2]}), maxSteps: 96, skinning: true}})); }});"
            + f" var skin = new THREE.MeshLambertMaterial({{color: new THREE.Color({', '.join(map(str, FLESH_COLOUR))})}});"
            + " for (var k = 0; k < 3; k++) { var bone = gltf.scene.getObjectByName('bone' + k);"
            + f"  var limb = new THREE.Mesh(new THREE.CylinderGeometry({FLESH}, {FLESH}, {third}, 32), skin);"
            + f"  limb.position.set(0, {third / 2}, 0); bone.add(limb);"
            + f"  bone.add(new THREE.Mesh(new THREE.SphereGeometry({FLESH}, 32, 16), skin)); }}"
            + " scene.add(new THREE.AmbientLight(0xffffff, 0.45));"
            + " var sun = new THREE.DirectionalLight(0xffffff, 0.8); sun.position.copy(camera.position); scene.add(sun);")


def blender_side(folder):
    """The Blender half, in ``folder``: the posed meshes as Workbench renders them, and the chain
    exported with the GLTF preset. Returns (Workbench panel, .glb bytes, export report, links,
    three.js camera)."""
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    chain, rig, links = chain_arm.build(bpy, scene, RADIUS, TURNS, LINK)
    chain.color = (*GOLD, 1.0)
    flesh(scene, rig)
    chain_arm.pose(rig)
    camera = chain_arm.camera_on_posed_arm(bpy, scene, chain)
    target = camera.location + camera.matrix_world.to_3x3() @ mathutils.Vector((0.0, 0.0, -1.0))
    three_camera = {"position": (TO_Y_UP @ np.array(camera.location)).tolist(),
                    "target": (TO_Y_UP @ np.array(target)).tolist(), "near": 0.5, "far": 100.0,
                    "fov": math.degrees(2 * math.atan(18.0 / camera.data.lens * min(1.0, H / W)))}  # 36 mm sensor on the longer side
    boxes = workbench_panel(scene, os.path.join(folder, "boxes.png"))
    path = os.path.join(folder, "chain.glb")
    report = export_scene.export_objects(bpy.context, [chain], "GLTF", path)
    with open(path, "rb") as f:
        return boxes, f.read(), report, links, three_camera


def main():
    parser = argparse.ArgumentParser(description="Writes idea.png: the box mesh in Blender beside the links three.js draws")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs"), help="folder to write idea.png into (default docs/)")
    out = os.path.join(parser.parse_args().out, "idea.png")
    reason = threejs.available()
    if reason:
        print(f"idea_picture: skipped, {reason}")
        return 0
    os.makedirs(os.path.dirname(out), exist_ok=True)
    # What Blender prints meanwhile (the bake's report, the EGL_BAD_MATCH lines of its first GPU
    # context, the render's and the glTF exporter's progress) is held back: shown only on failure.
    printed_out, printed_err = [], []
    try:
        with tempfile.TemporaryDirectory() as folder, blender_output.captured(1) as printed_out, \
                blender_output.captured(2) as printed_err:
            boxes, glb, report, links, three_camera = blender_side(folder)
    except Exception:
        sys.stderr.write("".join(line + "\n" for line in printed_out + printed_err))
        raise
    material = open(os.path.join(ROOT, "shaders", "threejs", "boxmarch.js")).read()
    start = time.perf_counter()
    links_panel = threejs.render(glb, material, setup_js(), W, H, three_camera).pixels
    gap = np.zeros((H, 4, 4), np.uint8)
    gap[..., :3], gap[..., 3] = 128, 255
    write_png(out, np.concatenate([boxes, gap, links_panel], axis=1))
    print(f"idea_picture: wrote {out} ({links} links, {report['layout']}, {time.perf_counter() - start:.1f} s in three.js)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

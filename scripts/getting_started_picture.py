"""docs/GETTING_STARTED.md's chain, end to end and headless, as the page tells it: one cube sized
as a link, an Array modifier whose offset object (an empty) moves each copy along and turns it a
quarter turn, the modifier applied (chain.blend); then the page's command line, `python3 -m
boxmarch pipeline chain.blend --steps bake,export --sort-axes-by-extent --preset GLTF --to
chain.glb`; then chain.glb drawn by the shipped three.js material (r111 in headless Chromium)
with every box a chain link, written to docs/getting_started_chain.png.

    python3 -m scripts.getting_started_picture [--out docs/getting_started_chain.png]
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

from scripts.threejs_picture import write_png
from tests.engines import threejs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK_SIZE = (0.46, 0.23, 0.06)  # the cube's Dimensions: length, width, wire thickness
LINKS, PITCH = 40, 0.36          # Array count; each copy 0.36 further along x, a quarter turn about x
WIDTH, HEIGHT = 640, 320
CAMERA = {"position": [3.0, 1.2, 2.2], "target": [4.5, 0.0, 0.0], "fov": 40, "near": 0.05, "far": 100.0}
LOOK = ("gltf.scene.traverse(function (o) { if (!o.isMesh) return;"
        " useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {map: 'return sdf_preset_link(p, box_half);',"
        " color: new THREE.Color(0.85, 0.65, 0.3)})); });")


def make_chain(path):
    """The page's Blender steps, by the operators the UI runs: the chain saved to ``path``."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add()
    chain = bpy.context.object
    chain.name = "Chain"
    chain.dimensions = LINK_SIZE
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    bpy.ops.object.empty_add(location=(PITCH, 0.0, 0.0), rotation=(math.radians(90.0), 0.0, 0.0))
    offset = bpy.context.object
    array = chain.modifiers.new("Array", "ARRAY")
    array.count = LINKS
    array.use_relative_offset = False
    array.use_object_offset = True
    array.offset_object = offset
    bpy.ops.object.select_all(action="DESELECT")
    chain.select_set(True)
    bpy.context.view_layer.objects.active = chain
    bpy.ops.object.modifier_apply(modifier="Array")
    bpy.data.objects.remove(offset)
    bpy.ops.wm.save_as_mainfile(filepath=path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "getting_started_chain.png"))
    args = parser.parse_args()
    reason = threejs.available()
    if reason:
        print(f"getting_started_picture: {reason}")
        return 1
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="boxmarch-chain-") as folder:
        blend, glb = os.path.join(folder, "chain.blend"), os.path.join(folder, "chain.glb")
        make_chain(blend)
        subprocess.run([sys.executable, "-m", "boxmarch", "pipeline", blend, "--steps", "bake,export",
                        "--sort-axes-by-extent", "--preset", "GLTF", "--to", glb], check=True, cwd=folder)
        material = open(os.path.join(ROOT, "shaders", "threejs", "boxmarch.js")).read()
        shot = threejs.render(open(glb, "rb").read(), material, LOOK, WIDTH, HEIGHT, CAMERA)
    write_png(args.out, shot.pixels)
    print(f"getting_started_picture: {args.out} ({WIDTH} x {HEIGHT}, three.js r111, {time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # bpy 4.2 and 4.5 crash at exit (docs/PLATFORMS.md)

"""docs/GETTING_STARTED.md's chain, end to end and headless, as the page tells it: one cube sized
as a link, an Array modifier whose offset object (an empty) moves each copy along and turns it a
quarter turn, the modifier applied (chain.blend); then the page's command line, `python3 -m
boxmarch pipeline chain.blend --steps bake,export --preset GLTF --to
chain.glb` (and the same with --preset GODOT3); then each file drawn with every box a chain link:
chain.glb by the shipped three.js material (r111 in headless Chromium), written to
docs/getting_started_chain.png, and the GODOT3 export as engines/godot3/README.md sets it up
(imported uncompressed, the shipped shader with map() = sdf_preset_link, box_table = the export's
.boxes.tres) by Godot 3.2 under xvfb, written to docs/godot3_chain.png.

    .venv-demo/bin/python -m scripts.getting_started_picture [--out-folder docs]

Any Python with the bpy module and boxmarch runs it (.venv-test's too). The three.js picture needs
what the demo installs (Chromium, three.js r111); the Godot 3 picture needs Godot 3 and xvfb
(scripts/setup.sh installs them): without them it is left out, with a line saying so.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

from tests.engines import godot3, threejs

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK_SIZE = (0.46, 0.23, 0.06)  # the cube's Dimensions: length, width, wire thickness
LINKS, PITCH = 40, 0.36          # Array count; each copy 0.36 further along x, a quarter turn about x
WIDTH, HEIGHT = 640, 320
CAMERA = {"position": [3.0, 1.2, 2.2], "target": [4.5, 0.0, 0.0], "fov": 40, "near": 0.05, "far": 100.0}
GODOT3_MAP = "return sdf_preset_link(p, h);"  # engines/godot3/README.md, step 5
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


def export(blend, preset, path, folder):
    """The page's command line: bake ``blend`` and export it with ``preset`` to ``path``."""
    subprocess.run([sys.executable, "-m", "boxmarch", "pipeline", blend, "--steps", "bake,export",
                    "--preset", preset, "--to", path], check=True, cwd=folder)


def godot3_picture(blend, folder):
    """The GODOT3 export of ``blend`` as engines/godot3/README.md sets it up, drawn by Godot 3."""
    godot_glb = os.path.join(folder, "godot", "chain.glb")
    os.makedirs(os.path.dirname(godot_glb))
    export(blend, "GODOT3", godot_glb, folder)
    project = os.path.join(folder, "project")
    table = open(os.path.join(folder, "godot", "chain.boxes.tres"), "rb").read()
    godot3.import_gltf(open(godot_glb, "rb").read(), project, compress=False, extra_files={"model.boxes.tres": table})
    return godot3.render(project, godot3.shipped_shader(GODOT3_MAP), width=WIDTH, height=HEIGHT, camera=CAMERA,
                         uniforms={"box_table": "res://model.boxes.tres"})


def write_png(path, rgba):
    """threejs_picture.write_png, imported when called: make_chain runs inside Blender's own
    Python, where boxmarch (which threejs_picture imports for the demo's character) is not on the path."""
    from scripts.threejs_picture import write_png as write

    write(path, rgba)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out-folder", default=os.path.join(ROOT, "docs"))
    args = parser.parse_args()
    reason = threejs.available()
    if reason:
        print(f"getting_started_picture: {reason} (bash scripts/demo.sh installs it)")
        return 1
    godot_missing = godot3.available()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="boxmarch-chain-") as folder:
        blend = os.path.join(folder, "chain.blend")
        make_chain(blend)
        glb = os.path.join(folder, "chain.glb")
        export(blend, "GLTF", glb, folder)
        material = open(os.path.join(ROOT, "shaders", "threejs", "boxmarch.js")).read()
        shots = {"getting_started_chain.png": threejs.render(open(glb, "rb").read(), material, LOOK, WIDTH, HEIGHT,
                                                             CAMERA)}
        if godot_missing:
            print(f"getting_started_picture: godot3_chain.png not made: {godot_missing} (bash scripts/setup.sh "
                  "installs Godot 3 and xvfb)")
        else:
            shots["godot3_chain.png"] = godot3_picture(blend, folder)
    for name, shot in shots.items():
        write_png(os.path.join(args.out_folder, name), shot.pixels)
        print(f"getting_started_picture: {os.path.join(args.out_folder, name)} ({WIDTH} x {HEIGHT})")
    print(f"getting_started_picture: {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # bpy 4.2 and 4.5 crash at exit (docs/PLATFORMS.md)

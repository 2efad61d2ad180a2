"""Renders the demo's demo.glb in Debian's three.js r111 (headless Chromium, software WebGL) with the
shipped ShaderMaterial (shaders/threejs/boxmarch.js), seen from the demo camera, to a PNG: the
character's bones turned by the demo's pose (boxmarch.demo_character.POSE; the file holds the
rest pose and the skin), the mannequin's boxes drawn as capsules, the chains as links, the
pebbles as capsules too. Run by scripts/demo.sh after the demo.

    python3 -m scripts.threejs_picture [--out demo_out]    (writes demo_out/demo_threejs.png)
"""
import argparse
import json
import math
import os
import sys
import time
import zlib
import struct

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
from boxmarch import demo_character  # noqa: E402
from tests.engines import threejs  # noqa: E402

TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # Blender -> glTF axes
WIDTH, HEIGHT = demo_character.PICTURE_SIZE
# The demo's Blender camera (a lens on a 36 mm sensor fitted to the picture's width) in glTF's axes.
CAMERA = {"position": (TO_Y_UP @ demo_character.CAMERA["location"]).tolist(),
          "target": (TO_Y_UP @ demo_character.CAMERA["target"]).tolist(),
          "fov": math.degrees(2 * math.atan(18.0 / demo_character.CAMERA["lens"] * HEIGHT / WIDTH)),
          "near": 1.0, "far": 100.0}


def pose_js():
    """Turns three.js's bones as the demo turns Blender's (tests/engines/threejs.pose_bones_js)."""
    turns = {name: TO_Y_UP @ np.asarray(axis, float) for name, (axis, _degrees) in demo_character.POSE.items()}
    angles = {name: math.radians(degrees) for name, (_axis, degrees) in demo_character.POSE.items()}
    return threejs.pose_bones_js(turns, angles)


def materials_js(looks=None):
    """Gives each mesh of the file the shipped material drawing its object's preview SDF in its
    colour (``looks``: object name -> (SDF, colour), demo_character.LOOKS by default); a skinned
    mesh gets the skinning material, and is never culled (its bounds are the rest pose's)."""
    looks = {name: [f"return sdf_preset_{sdf.lower()}(p, box_half);", colour]
             for name, (sdf, colour) in (looks or demo_character.LOOKS).items()}
    return ("var looks = " + json.dumps(looks, allow_nan=False) + ", drawn = {};"
            "gltf.scene.traverse(function (o) { if (!o.isMesh) return;"
            " var name = Object.keys(looks).filter(function (k) {"
            "   return o.name.indexOf(k) === 0 || (o.parent && o.parent.name.indexOf(k) === 0); })[0];"
            " if (!name) { o.visible = false; return; }"
            " var look = looks[name]; drawn[name] = true; if (o.isSkinnedMesh) o.frustumCulled = false;"
            " useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {map: look[0],"
            " color: new THREE.Color(look[1][0], look[1][1], look[1][2]), maxSteps: 96,"
            " skinning: !!o.isSkinnedMesh})); });"
            "Object.keys(looks).forEach(function (k) { if (!drawn[k]) throw new Error('no mesh ' + k); });")


def write_png(path, rgba):
    """8-bit RGBA PNG over a dark background (what the page leaves transparent), atomically."""
    height, width, _ = rgba.shape
    alpha = rgba[..., 3:4] / 255.0
    rgb = (rgba[..., :3] * alpha + 20 * (1 - alpha)).round().astype("uint8")
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(height))
    chunk = lambda kind, data: (struct.pack(">I", len(data)) + kind + data
                                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    temp = path + ".partial"
    with open(temp, "wb") as f:
        f.write(png)
    os.replace(temp, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="demo_out", help="the demo's output folder (default ./demo_out)")
    args, _demo_options = parser.parse_known_args()
    reason = threejs.available()
    if reason:
        print(f"threejs_picture: skipped, {reason}")
        return 0
    glb = os.path.join(args.out, "demo.glb")
    material = open(os.path.join(ROOT, "shaders", "threejs", "boxmarch.js")).read()
    start = time.perf_counter()
    shot = threejs.render(open(glb, "rb").read(), material, pose_js() + materials_js(), WIDTH, HEIGHT, CAMERA)
    path = os.path.join(args.out, "demo_threejs.png")
    write_png(path, shot.pixels)
    print(f"threejs_picture: {path} ({WIDTH} x {HEIGHT}, three.js r111 in Chromium, "
          f"{len(demo_character.POSE)} bones turned, {time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

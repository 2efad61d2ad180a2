"""Renders the demo's demo.glb in Debian's three.js r111 (headless Chromium, software WebGL) with the
shipped ShaderMaterial (shaders/threejs/boxmarch.js), seen from the demo camera, to a PNG: the
world's boxes as rounded boxes, the chains as links. Run by scripts/demo.sh after the demo.

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

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
from tests.engines import threejs  # noqa: E402

# The demo's Blender camera (demo._camera: at (0, -24, 3), turned 85 degrees about x, 30 mm
# lens on a 36 mm sensor fitted to the 640 px width) in glTF's Y-up axes (x, z, -y).
WIDTH, HEIGHT = 640, 360
TILT = math.radians(85.0)
POSITION = [0.0, 3.0, 24.0]
DIRECTION = [0.0, -math.cos(TILT), -math.sin(TILT)]
VERTICAL_FOV = math.degrees(2 * math.atan(18.0 / 30.0 * HEIGHT / WIDTH))
CAMERA = {"position": POSITION, "target": [p + 24.0 * d for p, d in zip(POSITION, DIRECTION)],
          "fov": VERTICAL_FOV, "near": 0.1, "far": 200.0}
# Mesh name prefix -> (map() body, colour): as the demo's Blender preview draws them.
LOOKS = {"Chains": ("return sdf_preset_link(p, box_half);", (0.85, 0.65, 0.3)),
         "": ("return sdf_preset_rounded_box(p, box_half);", (0.7, 0.75, 0.8))}


def setup_js():
    looks = json.dumps({k: [v[0], v[1]] for k, v in LOOKS.items()}, allow_nan=False)
    return ("var looks = " + looks + ";"
            "gltf.scene.traverse(function (o) { if (!o.isMesh) return;"
            " var name = o.name + ' ' + (o.parent ? o.parent.name : ''), look = looks[''];"
            " for (var k in looks) { if (k && name.indexOf(k) >= 0) look = looks[k]; }"
            " useBoxmarchMaterial(THREE, o, createBoxmarchMaterial(THREE, {map: look[0],"
            " color: new THREE.Color(look[1][0], look[1][1], look[1][2]), maxSteps: 96})); });")


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
    shot = threejs.render(open(glb, "rb").read(), material, setup_js(), WIDTH, HEIGHT, CAMERA)
    path = os.path.join(args.out, "demo_threejs.png")
    write_png(path, shot.pixels)
    print(f"threejs_picture: {path} ({WIDTH} x {HEIGHT}, three.js r111 in Chromium, "
          f"{time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Boxes against triangles: the same chain of links as boxmarch boxes and as triangle meshes that
stay within 1 pixel of the link's true silhouette.

The link is the LINK preset of scripts/chain_arm.py's links (0.46 x 0.23 x 0.06 box, sdf.glsl's
sd_link: a tube of radius r2 swept along a stadium path, two straight runs of 2 le and two half
circles of radius r1). Its triangle mesh: n rings of the tube's cross-section (vertices on the
true surface) along the path, each half circle in m segments, each straight run one segment:
n (2m + 2) vertices and 2 n (2m + 2) triangles. The surface between vertices lies inside the true
one by at most the two chords' sagittas,

    e(n, m) = r2 (1 - cos(pi / n)) + (r1 + r2) (1 - cos(pi / (2 m))),

(the tube's polygon, and the outer edge of the path's polygon), which this bench checks against
the exact SDF sampled over every triangle (the *measured* column). At a distance z from a camera of
vertical field of view fov, one pixel of an image h pixels tall spans 2 z tan(fov / 2) / h: the
mesh of the fewest triangles with e(n, m) under that, at the nearest link's distance, is the
1-pixel mesh of the scene.

Per link: triangles, vertex bytes (float32 position and normal, 24 bytes a vertex; indices 4
bytes each on top), against one box (12 triangles; 8 vertices drawn indexed, 24 in a glTF export
where Blender splits a flat box's corners by face) whose vertex bytes depend on the export
layout (float32 position and the layout's float32 channels, formats/layouts.py). Draw calls: one
for the box mesh; one for the triangle chain merged into one mesh (one per link as separate
objects).

Frame times (Blender's gpu module offscreen, Mesa llvmpipe, software rendering on this machine's
CPU cores: not a GPU, where the balance differs): chains of 1,000, 10,000 and 100,000 links laid
in rows (alternate links turned 90 degrees about the chain's axis) under a camera looking down
that frames them, each drawn as the preview draws the baked boxes (default settings) and as its
1-pixel triangle mesh (one draw, Lambert shading in the fragment stage), clear to a 1-pixel
read-back, best of REPEATS in round robin; wall and process CPU time.

    PYTHONPATH=addon python3 -m bench.bench_boxes_vs_triangles [--links 1000 10000 100000]
"""
import argparse
import math
import os
import sys
import time

import numpy as np

from scripts.chain_arm import LINK

HALF = LINK / 2
THICKNESS = min(HALF[2], 0.25 * min(HALF[0], HALF[1]))  # sdf.glsl sdf_preset_link
LE, R1, R2 = max(HALF[0] - HALF[1], 0.0), HALF[1] - THICKNESS, THICKNESS
FOV = 40.0  # degrees, bench_gpu_cost.camera's
SIZE = (960, 540)
REPEATS = 5
CHANNEL_BYTES = {"COLOR": 16, "NORMAL": 12, "TANGENT": 16}  # float32; UVn: 8


def link_radii(half):
    """(le, r1, r2) of sdf.glsl's sdf_preset_link for a box of half-extents ``half`` (..., 3),
    longest axis first: the straight runs' half length, the path's radius, the wire's radius."""
    half = np.asarray(half, np.float64)
    thickness = np.minimum(half[..., 2], 0.25 * np.minimum(half[..., 0], half[..., 1]))
    return np.maximum(half[..., 0] - half[..., 1], 0.0), half[..., 1] - thickness, thickness


def link_distance(p, half=HALF):
    """sd_link of the LINK preset at box-local points p (float64), as sdf.glsl has it (p.yxz), in
    a box of half-extents ``half`` (longest axis first; broadcast against p's points)."""
    le, r1, r2 = link_radii(half)
    qy = np.maximum(np.abs(p[..., 0]) - le, 0.0)
    return np.hypot(np.hypot(p[..., 1], qy) - r1, p[..., 2]) - r2


def chord_error(n, m):
    return R2 * (1 - math.cos(math.pi / n)) + (R1 + R2) * (1 - math.cos(math.pi / (2 * m)))


def fewest_triangles(error):
    """(n, m) of the fewest triangles whose chord error is at most ``error``."""
    best = None
    for n in range(3, 257):
        if R2 * (1 - math.cos(math.pi / n)) >= error:
            continue
        m = 1
        while chord_error(n, m) > error:
            m += 1
        if best is None or n * (m + 1) < best[0] * (best[1] + 1):
            best = (n, m)
    return best


def link_mesh(n, m, half=HALF):
    """(positions (V, 3), normals (V, 3), triangles (T, 3)) of the link mesh, box-local, for a box
    of half-extents ``half`` (longest axis first); triangles wound counter-clockwise seen from
    outside."""
    le, r1, r2 = (float(v) for v in link_radii(half))
    # path rings: half circle at x = +le (angles -90..90 degrees), then at x = -le (90..270)
    angles = np.concatenate([np.linspace(-np.pi / 2, np.pi / 2, m + 1), np.linspace(np.pi / 2, 3 * np.pi / 2, m + 1)])
    ends = np.repeat([le, -le], m + 1)
    outward = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    path = outward * r1 + np.column_stack([ends, np.zeros((len(ends), 2))])
    phi = 2 * np.pi * np.arange(n) / n
    normals = (np.cos(phi)[None, :, None] * outward[:, None, :] + np.sin(phi)[None, :, None] * [0.0, 0.0, 1.0])
    positions = path[:, None, :] + r2 * normals
    rings = len(path)
    a = np.arange(rings)[:, None] * n + np.arange(n)[None, :]
    b = ((np.arange(rings)[:, None] + 1) % rings) * n + np.arange(n)[None, :]
    a1, b1 = np.roll(a, -1, axis=1), np.roll(b, -1, axis=1)
    triangles = np.concatenate([np.stack([a, b, b1], -1), np.stack([a, b1, a1], -1)]).reshape(-1, 3)
    return positions.reshape(-1, 3), normals.reshape(-1, 3), triangles


def measured_error(n, m, samples=12):
    """Largest |SDF| over a barycentric grid on every triangle of the (n, m) mesh."""
    positions, _normals, triangles = link_mesh(n, m)
    u, v = np.meshgrid(np.linspace(0, 1, samples + 1), np.linspace(0, 1, samples + 1))
    keep = u + v <= 1
    u, v = u[keep], v[keep]
    corners = positions[triangles]
    points = (corners[:, None, 0] * (1 - u - v)[:, None] + corners[:, None, 1] * u[:, None]
              + corners[:, None, 2] * v[:, None])
    return float(np.abs(link_distance(points)).max())


def pixel_width(distance, height):
    return 2 * distance * math.tan(math.radians(FOV) / 2) / height


def layout_bytes():
    """{layout: float32 bytes per vertex}: position and the layout's channels."""
    from boxmarch.formats import layouts

    return {name: 12 + sum(CHANNEL_BYTES.get(c, 8) for c in layout.channels) for name, layout in layouts.LAYOUTS.items()}


def chain_rows(count, size=SIZE):
    """A chain of ``count`` links in rows along x (links 0.36 apart, alternate ones turned 90
    degrees about x), rows 0.3 apart in y, and a camera looking down -z that frames them in an
    image of ``size`` (width, height): (origins, rotations, half-extents, sdf, (object_to_clip,
    object_to_view, eye))."""
    from bench.bench_gpu_cost import camera

    per_row = math.ceil(math.sqrt(count * 0.3 / 0.36))
    k = np.arange(count)
    origins = np.column_stack([0.36 * (k % per_row), 0.3 * (k // per_row), np.zeros(count)])
    origins -= (origins.max(0) + origins.min(0)) / 2
    turn = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    rotations = np.where((k % 2 == 1)[:, None, None], turn, np.eye(3))
    extent = np.abs(origins).max(0)[:2] + LINK[0]
    tan = math.tan(math.radians(FOV) / 2)
    distance = max(extent[1], extent[0] * size[1] / size[0]) / tan
    eye = (0.0, 0.0, distance)
    to_clip, to_view, eye4 = camera(eye, (0.0, 0.0, 0.0), *size, up=(0.0, 1.0, 0.0))
    return origins, rotations, np.tile(HALF, (count, 1)), "LINK", (to_clip, to_view, eye4)


def equal_error_rows():
    """Per-link counts at the chain down the arm's camera (its nearest link) and at two sizes."""
    from bench.bench_gpu_cost import camera
    from scripts import chain_arm

    centres, _rotations = chain_arm.chain_geometry()
    eye = np.array([0.4, -1.2, 14.0])
    _to_clip, to_view, _ = camera(eye, (0.0, 0.0, 4.5), *SIZE)
    nearest = float(np.min(-(centres @ to_view[:3, :3].T + to_view[:3, 3])[:, 2])) - HALF[0]
    rows = []
    for height in (540, 1080):
        error = pixel_width(nearest, height)
        n, m = fewest_triangles(error)
        rows.append(mesh_row(f"chain down the arm, nearest link {nearest:.1f} units, {height} px tall", error, n, m))
    return rows


def mesh_row(label, error, n, m):
    vertices, triangles = n * (2 * m + 2), 2 * n * (2 * m + 2)
    return [label, f"{error * 1e3:.2f}", f"{n} x {2 * m + 2}", f"{chord_error(n, m) * 1e3:.2f}",
            f"{measured_error(n, m) * 1e3:.2f}", f"{triangles}", f"{vertices}", f"{24 * vertices}",
            f"{12 * triangles}"]


MESH_HEADERS = ["where", "1 px (1e-3 units)", "tube x path segments", "chord error formula (1e-3)",
                "measured max abs SDF (1e-3)", "triangles per link", "vertices", "vertex bytes", "index bytes"]


TRIANGLE_VERTEX = """
void main()
{
  gl_Position = to_clip * vec4(pos, 1.0);
  normal_view = mat3(to_view) * nor;
}
"""
TRIANGLE_FRAGMENT = """
void main()
{
  vec3 n = normalize(normal_view);
  frag_color = vec4(vec3(0.8) * (0.35 + 0.65 * max(n.z, 0.0)), 1.0);
}
"""

# The normal as the preview's NORMAL output writes it (0.5 + 0.5 n; n in object space when to_view
# is the identity)
NORMAL_FRAGMENT = """
void main()
{
  frag_color = vec4(0.5 + 0.5 * normalize(normal_view), 1.0);
}
"""


def triangle_shader(fragment=TRIANGLE_FRAGMENT):
    """A lit-mesh shader: position and normal in, Lambert from the view axis out (``fragment``:
    another fragment stage of the same interface, e.g. NORMAL_FRAGMENT)."""
    import gpu

    interface = gpu.types.GPUStageInterfaceInfo("bm_triangles")
    interface.smooth("VEC3", "normal_view")
    info = gpu.types.GPUShaderCreateInfo()
    info.push_constant("MAT4", "to_clip")
    info.push_constant("MAT4", "to_view")
    info.vertex_in(0, "VEC3", "pos")
    info.vertex_in(1, "VEC3", "nor")
    info.vertex_out(interface)
    info.fragment_out(0, "VEC4", "frag_color")
    info.vertex_source(TRIANGLE_VERTEX)
    info.fragment_source(fragment)
    return gpu.shader.create_from_info(info)


def chain_mesh(scene, n, m):
    """The chain's triangle mesh in object space: (positions, normals, triangles); every link of
    the scene the same size."""
    origins, rotations, half, _sdf, _camera = scene
    if not np.allclose(half, half[0]):
        raise ValueError("chain_mesh: the links differ in size")
    positions, normals, triangles = link_mesh(n, m, half[0])
    world = np.einsum("kij,vj->kvi", rotations, positions) + origins[:, None, :]
    world_normals = np.einsum("kij,vj->kvi", rotations, normals)
    offsets = (np.arange(len(origins)) * len(positions))[:, None, None]
    return (world.reshape(-1, 3).astype(np.float32), world_normals.reshape(-1, 3).astype(np.float32),
            (triangles[None] + offsets).reshape(-1, 3).astype(np.uint32))


def timed_rows(bpy, count):
    import gpu
    from gpu_extras.batch import batch_for_shader

    from bench.bench_preview_cost import baked_object
    from bench.common import best_of, offscreen_frame, preview_frame

    scene = chain_rows(count)
    to_clip, to_view, eye = scene[4]
    nearest = float(eye[2]) - HALF[1]  # the links lie in z = 0, the turned ones upright
    n, m = fewest_triangles(pixel_width(nearest, SIZE[1]))
    positions, normals, triangles = chain_mesh(scene, n, m)
    shader = triangle_shader()
    batch = batch_for_shader(shader, "TRIS", {"pos": positions, "nor": normals}, indices=triangles)
    ob = baked_object(bpy, f"chain {count}", scene)
    projection = to_clip @ np.linalg.inv(to_view)
    offscreen = gpu.types.GPUOffScreen(*SIZE, format="RGBA32F")

    def boxes(read=False):
        return preview_frame(offscreen, ob, to_view, projection, read)

    def draw_mesh():
        shader.bind()
        shader.uniform_float("to_clip", to_clip.T.ravel().tolist())
        shader.uniform_float("to_view", to_view.T.ravel().tolist())
        batch.draw(shader)

    def mesh(read=False):
        return offscreen_frame(offscreen, draw_mesh, read)

    images = {name: draw(read=True) for name, draw in (("boxes", boxes), ("mesh", mesh))}
    if os.environ.get("BM_DUMP"):
        np.savez(os.environ["BM_DUMP"] + f"_{count}.npz", **images)
    covered = {name: image[..., 3] > 0 for name, image in images.items()}
    best = {"boxes": [math.inf, math.inf], "mesh": [math.inf, math.inf]}
    for _ in range(REPEATS):
        for name, draw in (("boxes", boxes), ("mesh", mesh)):
            cpu = time.process_time()
            wall = best_of(1, draw)
            best[name] = [min(best[name][0], wall), min(best[name][1], time.process_time() - cpu)]
    either = max(int((covered["boxes"] | covered["mesh"]).sum()), 1)
    differs = (covered["boxes"] != covered["mesh"]).sum() / either
    bpy.data.objects.remove(ob)
    return [f"{count:,}", f"{LINK[0] / pixel_width(nearest, SIZE[1]):.1f}", f"{n} x {2 * m + 2}",
            f"{len(triangles):,}", f"{positions.nbytes + normals.nbytes:,}",
            f"{best['mesh'][0] * 1e3:.0f} / {best['mesh'][1] * 1e3:.0f}", f"{12 * count:,}",
            f"{8 * layout_bytes()['CLASSIC'] * count:,}",
            f"{best['boxes'][0] * 1e3:.0f} / {best['boxes'][1] * 1e3:.0f}",
            f"{best['mesh'][0] / best['boxes'][0]:.2f}x", f"{100 * covered['boxes'].mean():.1f}%", f"{100 * differs:.2f}%"]


TIMED_HEADERS = ["links", "link length (px)", "tube x path", "triangles", "mesh vertex bytes", "mesh ms (wall / CPU)",
                 "box triangles", "box vertex bytes (CLASSIC)", "boxes ms (wall / CPU)", "boxes' speed-up", "image covered",
                 "coverage differs"]


def main():
    from bench.common import table

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--links", type=int, nargs="*", default=[1000, 10000, 100000],
                        help="chain lengths to time on llvmpipe (none: the counts only)")
    args = parser.parse_args()
    print(f"link {LINK.tolist()} (le {LE:.4f}, r1 {R1:.4f}, r2 {R2:.4f}), field of view {FOV} degrees")
    print(table(MESH_HEADERS, equal_error_rows()))
    per_layout = layout_bytes()
    print(table(["box layout", "bytes per vertex", "vertex bytes per box (8 vertices, indexed)",
                 "per box in a glTF export (24 vertices)"],
                [[name, f"{b}", f"{8 * b}", f"{24 * b}"] for name, b in per_layout.items()]))
    if not args.links:
        return
    import bpy
    import gpu

    import boxmarch
    from boxmarch import preview

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    preview.ensure_gpu_context()
    rows = [timed_rows(bpy, count) for count in args.links]
    print(f"Blender {bpy.app.version_string}, {gpu.platform.renderer_get()}, {SIZE[0]} x {SIZE[1]} px, "
          f"best of {REPEATS}, one draw call each")
    print(table(TIMED_HEADERS, rows))
    sys.stdout.flush()
    os._exit(0)  # bpy modules with registered add-ons may crash at exit (shared notes)


if __name__ == "__main__":
    main()

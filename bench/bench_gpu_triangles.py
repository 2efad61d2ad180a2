"""Boxes against triangles on a GPU, without Blender: the chains of bench_boxes_vs_triangles.py
(1,000, 10,000 and 100,000 links in rows under a camera looking down) drawn as the preview draws
their baked boxes (bench/gl_preview.py: what draw_object does by default) and as the triangle
mesh whose silhouette stays within 1 pixel of the true link at that size (the same mesh and
Lambert shader as bench_boxes_vs_triangles.py), through headless EGL + OpenGL 4.3, each frame
timed on the GPU (GL_TIME_ELAPSED), into the RGBA16F + DEPTH24_STENCIL8 framebuffer of
bench_gpu_frame.py.

Per chain and size: the mesh's tube x path segments, triangles, vertex and index bytes; the
boxes' triangles, vertex bytes (as the CLASSIC export writes them, 8 vertices a box) and draw
calls; GPU ms per frame of each (median of the frames, lower of two passes), and the share of
covered pixels where the two disagree on coverage.

    PYTHONPATH=addon python3 -m bench.gpu_frame_data DATA --chains 1000,10000,100000   # here
    python3 -m bench.bench_gpu_triangles DATA/chains [--json OUT.json]               # a GPU machine

Needs numpy and PyOpenGL (gl_headless.py)."""
import argparse
import json
from pathlib import Path

import numpy as np

from bench import chain_data
from bench.bench_boxes_vs_triangles import (HALF, LINK, TRIANGLE_FRAGMENT, TRIANGLE_VERTEX, chain_mesh,
                                            fewest_triangles, pixel_width)
from bench.common import table
from bench.gl_headless import GL, egl_context, framebuffer, program, read_back, timed_frames
from bench.gl_preview import PreviewObject, begin_frame, shipped_arguments

SIZES = ((960, 540), (1920, 1080))
DECLARATIONS = {"vert": "#version 430 core\nuniform mat4 to_clip;\nuniform mat4 to_view;\n"
                        "layout(location = 0) in vec3 pos;\nlayout(location = 1) in vec3 nor;\nout vec3 normal_view;\n",
                "frag": "#version 430 core\nin vec3 normal_view;\nlayout(location = 0) out vec4 frag_color;\n"}


class TriangleMesh:
    """The chain's 1-pixel triangle mesh at one image height, in one draw."""

    def __init__(self, stored, height):
        to_clip, to_view = stored["object_to_clip"], stored["object_to_view"]
        eye_height = -float(to_view[2, 3])  # the camera looks down -z from (0, 0, eye_height)
        self.nearest = eye_height - HALF[1]  # the links lie in z = 0, the turned ones upright
        self.segments = fewest_triangles(pixel_width(self.nearest, height))
        origins = stored["origins"].astype(np.float64)
        scene = (origins, stored["rotations"].astype(np.float64), np.tile(HALF, (len(origins), 1)), None, None)
        positions, normals, triangles = chain_mesh(scene, *self.segments)
        self.triangles = len(triangles)
        self.vertex_bytes, self.index_bytes = positions.nbytes + normals.nbytes, triangles.nbytes
        self.program = program(DECLARATIONS["vert"] + TRIANGLE_VERTEX, DECLARATIONS["frag"] + TRIANGLE_FRAGMENT)
        GL.glUseProgram(self.program)
        for name, matrix in (("to_clip", to_clip), ("to_view", to_view)):
            GL.glUniformMatrix4fv(GL.glGetUniformLocation(self.program, name), 1, GL.GL_TRUE,
                                  np.asarray(matrix, np.float32))
        self.vao = GL.glGenVertexArrays(1)
        GL.glBindVertexArray(self.vao)
        for location, values in enumerate((positions, normals)):
            buffer = GL.glGenBuffers(1)
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
            GL.glBufferData(GL.GL_ARRAY_BUFFER, values.nbytes, values, GL.GL_STATIC_DRAW)
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(location, 3, GL.GL_FLOAT, GL.GL_FALSE, 0, None)
        self.elements = GL.glGenBuffers(1)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self.elements)
        GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, triangles.nbytes, triangles, GL.GL_STATIC_DRAW)

    def draw(self, target, width, height):
        begin_frame(target, width, height)
        GL.glUseProgram(self.program)
        GL.glBindVertexArray(self.vao)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self.elements)
        GL.glDrawElements(GL.GL_TRIANGLES, 3 * self.triangles, GL.GL_UNSIGNED_INT, None)

    def free(self):
        GL.glDeleteVertexArrays(1, [self.vao])


def measure_chain(stored, passes):
    """Rows of the table for one chain, one per size."""
    boxes = PreviewObject({**stored, **chain_data.expand(stored)})
    count = int(stored["boxes"])
    rows = []
    for width, height in SIZES:
        shipped = shipped_arguments(stored, f"{width}x{height}")
        mesh = TriangleMesh(stored, height)
        fbo = framebuffer(width, height)
        frames = {"boxes": lambda: boxes.draw(fbo, width, height, **shipped),
                  "mesh": lambda: mesh.draw(fbo, width, height)}
        covered, best = {}, {}
        for name, frame in frames.items():
            boxes.draws = 0
            frame()
            covered[name] = read_back(width, height)[1] < 1.0
            if name == "boxes":
                draw_calls = boxes.draws
        for _ in range(passes):  # round robin
            for name, frame in frames.items():
                best.setdefault(name, []).append(float(np.median(timed_frames(frame))))
        either = max(int((covered["boxes"] | covered["mesh"]).sum()), 1)
        n, m = mesh.segments
        rows.append({"links": count, "size": f"{width}x{height}", "link_px": float(LINK[0] / pixel_width(mesh.nearest, height)),
                     "segments": f"{n} x {2 * m + 2}", "mesh_triangles": mesh.triangles,
                     "mesh_vertex_bytes": int(mesh.vertex_bytes), "mesh_index_bytes": int(mesh.index_bytes),
                     "mesh_ms": best["mesh"], "box_triangles": 12 * count,
                     "box_vertex_bytes": int(stored["classic_vertex_bytes"]), "box_index_bytes": 36 * 4 * count,
                     "box_draw_calls": draw_calls, "resolved": shipped.get("resolved", False), "boxes_ms": best["boxes"],
                     "covered": float(covered["boxes"].mean()),
                     "coverage_differs": float((covered["boxes"] != covered["mesh"]).sum() / either)})
        mesh.free()
        GL.glDeleteFramebuffers(1, [fbo])
    return rows


def report(result):
    headers = ["links", "size", "link length (px)", "tube x path", "mesh triangles", "mesh vertex + index bytes", "mesh ms",
               "box triangles", "box vertex + index bytes (CLASSIC)", "box draw calls", "boxes ms", "boxes' speed-up",
               "image covered", "coverage differs"]
    rows = [[f"{r['links']:,}", r["size"], f"{r['link_px']:.1f}", r["segments"], f"{r['mesh_triangles']:,}",
             f"{r['mesh_vertex_bytes']:,} + {r['mesh_index_bytes']:,}", f"{min(r['mesh_ms']):.3f}",
             f"{r['box_triangles']:,}", f"{r['box_vertex_bytes']:,} + {r['box_index_bytes']:,}",
             f"{r['box_draw_calls']}{' (resolved)' if r['resolved'] else ''}", f"{min(r['boxes_ms']):.3f}",
             f"{min(r['mesh_ms']) / min(r['boxes_ms']):.2f}x", f"{100 * r['covered']:.1f}%",
             f"{100 * r['coverage_differs']:.2f}%"] for r in result["rows"]]
    return "\n".join([f"{result['renderer']} | OpenGL {result['version']}", table(headers, rows)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("chains", type=Path, help="folder of chain_N.npz written by bench/gpu_frame_data.py")
    parser.add_argument("--passes", type=int, default=2)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    egl_context()
    result = {"renderer": GL.glGetString(GL.GL_RENDERER).decode(), "version": GL.glGetString(GL.GL_VERSION).decode(),
              "rows": []}
    print(result["renderer"], "|", result["version"], flush=True)
    paths = sorted(args.chains.glob("chain_*.npz"), key=lambda p: int(p.stem.split("_")[1]))
    for path in paths:
        result["rows"] += measure_chain(dict(np.load(path)), args.passes)
        print(f"{path.stem}: done", flush=True)
        if args.json:
            args.json.write_text(json.dumps(result, indent=1, allow_nan=False))
    print(report(result))


if __name__ == "__main__":
    main()

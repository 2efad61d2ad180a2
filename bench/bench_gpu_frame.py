"""Viewport preview frame times on a GPU, without Blender: the preview's own shaders and vertex
buffers (written by bench/gpu_frame_data.py) drawn through headless EGL + OpenGL 4.3, each frame
timed on the GPU with a GL_TIME_ELAPSED query.

For each scene and size, the configurations:

* shipped: depth_greater declared (create-info depth_write GREATER), octant order, quality 1;
* undeclared: gl_FragDepth written without a declaration (Blender 3.4), octant order;
* file order: declared, the triangles in the mesh's order;
* undeclared, file order: neither technique (the cost model's "today");
* quality 0.5 and 0.25: shipped with the quality knob;
* diagnostics (not pictures the preview draws): face depth, the marched depth not written (early
  depth testing certainly on; the depth left is the face's, so wrong), in octant and file order;
  no discard, `discard` replaced by writing the cleared colour and depth (the same picture in
  this framebuffer), declared and undeclared: which of the two keeps the GPU's early test off;
  the declared shader under `#version 450 core`, and with `#extension GL_ARB_conservative_depth`;

and the naive full-screen raymarch over every box (bench/naive_fullscreen.frag.glsl) for the
cloud (measure_naive: the smallest size in one draw, larger ones in strips).

Frame: clear colour and depth, one draw call (the preview's state: depth test LESS_EQUAL, depth
writes on, no culling, no blending) into an RGBA16F + DEPTH24_STENCIL8 framebuffer.
Each configuration: warm-up frames, then frames until about BUDGET seconds of GPU time (at most
MAX_FRAMES); median and mean of the queries; the whole list is run twice (two passes) so the
spread between passes shows the noise.

Correctness at the reference size (960 x 540): the GPU's image and depth read back and compared
with the CPU reference (core.render_boxes) at the same quality: coverage agreement, depth error
where both hit (view-axis distance, in units of the scene), colour error of the shaded image;
and the fragment shader invocations of the frame (ARB_pipeline_statistics_query) per covered
pixel, which show whether the early depth test skipped any march.

    PYTHONPATH=addon python3 -m bench.gpu_frame_data DATA           # here, with the bpy module
    python3 -m bench.bench_gpu_frame DATA [--json OUT.json] [--sizes 960x540,1920x1080]
    EGL_PLATFORM=surfaceless python3 -m bench.bench_gpu_frame DATA --scenes cloud \
        --sizes 960x540 --naive-sizes 24x14,48x27 --passes 1      # Mesa llvmpipe, a few minutes

Needs numpy and PyOpenGL only (gl_headless.py), so it runs where Blender is absent (a GPU
machine: copy bench_gpu_frame.py, gl_headless.py, common.py and DATA). EGL: the default display
(NVIDIA: the GPU; Mesa: EGL_PLATFORM=surfaceless for llvmpipe without a display server).
"""
import argparse
import json
import time
from pathlib import Path

import numpy as np

from bench.common import table  # noqa: E402
from bench.gl_headless import (GL, counted, egl_context, framebuffer, program, read_back, timed_frames,  # noqa: E402
                               timed_frames_exact)
from bench.gl_preview import PreviewObject, fullscreen_triangle, shipped_arguments  # noqa: E402

REFERENCE_SIZE = (960, 540)
# (label, bench/gl_preview.py PreviewObject.draw's arguments) per set; the first of each set is
# the base its speed-ups and pixels changed are against.
CONFIG_SETS = {
    # what the preview draws: the march in one pass against the pre-pass and the resolved passes
    "passes": (("today", dict(fragment="undeclared", order="file")),
               ("depth_greater + octant order", dict()),
               ("+ back faces culled", dict(cull=True)),
               ("+ occluders + back faces culled, one pass", dict(cull=True, occluders=True)),
               ("+ resolved passes", dict(cull=True, occluders=True, resolved=True))),
    # does the depth declaration or the order keep early depth? (one pass, every face)
    "declaration": (("undeclared, file order", dict(fragment="undeclared", order="file")),
                    ("depth_greater + octant order", dict()),
                    ("undeclared", dict(fragment="undeclared")),
                    ("file order", dict(order="file")),
                    ("quality 0.5", dict(quality=0.5)), ("quality 0.25", dict(quality=0.25)),
                    ("face depth (diagnostic)", dict(fragment="face_depth")),
                    ("face depth, file order (diagnostic)", dict(fragment="face_depth", order="file")),
                    ("no discard (diagnostic)", dict(fragment="depth_greater_no_discard")),
                    ("undeclared, no discard (diagnostic)", dict(fragment="undeclared_no_discard")),
                    ("GLSL 4.50 (diagnostic)", dict(fragment="depth_greater_450")),
                    ("extension named (diagnostic)", dict(fragment="depth_greater_extension")))}
# The naive frame is drawn in strips (measure_naive): on the H100, 16 strips of 960 x 34 px queued
# at once returned nonsense timer values and an empty image (the driver stopping long GPU work).
NAIVE_ROWS = 4
NAIVE_BUDGET_MS = 20000.0
GL_FRAGMENT_SHADER_INVOCATIONS = 0x82F4  # ARB_pipeline_statistics_query


def view_distance(depth, object_to_clip, object_to_view):
    """View-axis distance of window depths (perspective projection of bench_gpu_cost.camera)."""
    projection = object_to_clip @ np.linalg.inv(object_to_view)
    return projection[2, 3] / ((2.0 * depth - 1.0) + projection[2, 2])


def compare(data, quality, rgba, depth):
    """GPU image against the CPU reference at ``quality``: coverage agreement, view-axis depth
    error where both hit (99th percentile and worst), colour error (99th percentile, of 1)."""
    reference = data[f"reference_depth_{quality}"]
    gpu_hit, cpu_hit = depth < 1.0, reference < 1.0
    both = gpu_hit & cpu_hit
    to_clip, to_view = data["object_to_clip"], data["object_to_view"]
    error = np.abs(view_distance(depth[both].astype(np.float64), to_clip, to_view)
                   - view_distance(reference[both].astype(np.float64), to_clip, to_view))
    result = {"coverage": float(gpu_hit.mean()), "coverage_agreement": float((gpu_hit == cpu_hit).mean()),
              "depth_error_p99": float(np.percentile(error, 99)) if error.size else 0.0,
              "depth_error_max": float(error.max()) if error.size else 0.0}
    if quality == 1.0:
        colour = np.abs(rgba[both][:, :3] - data["reference_rgba8"][both][:, :3] / 255.0).max(axis=1)
        result["colour_error_p99"] = float(np.percentile(colour, 99)) if colour.size else 0.0
    return result


def changed_pixels(image, depth, base_image, base_depth):
    """(pixels whose colour differs from the base's by more than 1/255, pixels whose depth differs
    at all, pixels covered in either image)."""
    covered = (depth < 1.0) | (base_depth < 1.0)
    colour = (np.abs(image - base_image).max(-1) > 1 / 255) & covered
    return int(colour.sum()), int(((depth != base_depth) & covered).sum()), int(covered.sum())


def measure_scene(data, sizes, passes, configs):
    """{config label: {size: {"median_ms": [per pass], "mean_ms": ..., "frames": ...}}} and, at
    REFERENCE_SIZE, each configuration's picture against the CPU reference and the first
    configuration's, and its fragment shader invocations."""
    drawn = PreviewObject(data)
    times, checks = {}, {}
    for width, height in sizes:
        fbo = framebuffer(width, height)
        base = None
        for label, arguments in configs:
            def frame():
                drawn.draw(fbo, width, height, **arguments)

            runs = [timed_frames(frame) for _ in range(passes)]
            times.setdefault(label, {})[f"{width}x{height}"] = {
                "median_ms": [float(np.median(r)) for r in runs], "mean_ms": [float(r.mean()) for r in runs],
                "frames": [len(r) for r in runs]}
            if (width, height) == REFERENCE_SIZE:
                invocations = counted(GL_FRAGMENT_SHADER_INVOCATIONS, frame)
                rgba, depth = read_back(width, height)
                base = base or (rgba, depth)
                check = compare(data, arguments.get("quality", 1.0), rgba, depth)
                check["shader_invocations"] = invocations
                check["colour_changed"], check["depth_changed"], check["covered"] = changed_pixels(rgba, depth, *base)
                checks[label] = check
        GL.glDeleteFramebuffers(1, [fbo])
    return times, checks


def shipped_label(data, size):
    """The configuration of the passes set that the preview draws at ``size`` (gl_preview.shipped_arguments)."""
    arguments = shipped_arguments(data, size)
    return next(label for label, drawn in CONFIG_SETS["passes"] if drawn == arguments)


def measure_naive(data, sizes):
    """GPU milliseconds of the naive full-screen frame, smallest size first: the first in one draw,
    larger ones in strips of NAIVE_ROWS rows, one draw each, so that no draw runs into the driver's
    time limit. Strips in a shuffled order; after NAIVE_BUDGET_MS the frame is projected from the
    strips drawn (their mean times the strip count). Coverage, steps per pixel, and at
    REFERENCE_SIZE the coverage agreement with the CPU reference (complete frames only)."""
    handle = program(data["source_naive_vertex"], data["source_naive_fragment"])
    boxes = np.ascontiguousarray(data["naive_boxes"], np.float32)
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA32F, 3, len(boxes), 0, GL.GL_RGBA, GL.GL_FLOAT, boxes)
    GL.glBindVertexArray(fullscreen_triangle())
    GL.glUseProgram(handle)
    clip_to_object = np.linalg.inv(data["object_to_clip"]).astype(np.float32)
    GL.glUniformMatrix4fv(GL.glGetUniformLocation(handle, "clip_to_object"), 1, GL.GL_TRUE, clip_to_object)
    GL.glUniform4f(GL.glGetUniformLocation(handle, "march"), *[float(v) for v in data["march"]])
    GL.glUniform1i(GL.glGetUniformLocation(handle, "boxes"), 0)
    result, first = {}, True
    for width, height in sorted(sizes, key=lambda size: size[0] * size[1]):
        fbo = framebuffer(width, height)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glUniform4i(GL.glGetUniformLocation(handle, "sizes"), len(boxes), width, height, 0)
        GL.glEnable(GL.GL_SCISSOR_TEST)
        if first:  # warm-up: one pixel, compiles outside the timing
            GL.glScissor(0, 0, 1, 1)
            GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
            GL.glFinish()
        # the smallest frame in one draw; larger ones in NAIVE_ROWS-row strips, in a shuffled order
        rows = height if first else NAIVE_ROWS
        starts = np.random.default_rng(0).permutation(np.arange(0, height, rows))
        strips, start = [], time.perf_counter()
        for y0 in starts:
            GL.glScissor(0, int(y0), width, min(rows, height - int(y0)))
            strips.append(float(timed_frames_exact(lambda: GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3), 1)[0]))
            if sum(strips) > NAIVE_BUDGET_MS:
                break
        GL.glDisable(GL.GL_SCISSOR_TEST)
        entry = {"ms": float(np.mean(strips)) * len(starts), "strips": [len(strips), len(starts)],
                 "wall_ms": (time.perf_counter() - start) * 1e3, "gl_error": int(GL.glGetError())}
        if len(strips) == len(starts):
            image = read_back(width, height)[0]
            naive_hit = image[..., 0] > 0.5
            entry.update(coverage=float(naive_hit.mean()), steps_per_pixel=float(image[..., 1].mean()))
            if (width, height) == REFERENCE_SIZE:
                entry["coverage_agreement"] = float((naive_hit == (data["reference_depth_1.0"] < 1.0)).mean())
        result[f"{width}x{height}"] = entry
        first = False
        GL.glDeleteFramebuffers(1, [fbo])
    return result


def parse_sizes(text):
    return [tuple(int(v) for v in size.split("x")) for size in text.split(",") if size]


def report(result):
    lines = [f"{result['renderer']} | OpenGL {result['version']}", ""]
    labels = result["configs"]
    base = labels[0]
    rows = []
    for scene, entry in result["scenes"].items():
        for size in entry["times"].get(base, {}):
            def ms(label):
                return min(entry["times"][label][size]["median_ms"])

            def cell(label):
                return f"{ms(label):.3f} ({ms(base) / ms(label):.2f}x)"
            shipped = entry["shipped"].get(size)
            rows.append([scene, size, *[cell(label) for label in labels]]
                        + ([f"{shipped}: {cell(shipped)}"] if shipped else []))
    headers = ["scene", "size", *labels] + (["shipped (the preview's choice)"] if result["set"] == "passes" else [])
    lines += [] if not rows else ["GPU ms per frame (median of the frames, lower of the passes; speed-up against "
              f"'{base}')", table(headers, rows), ""]
    rows = []
    for scene, entry in result["scenes"].items():
        for label, check in entry["checks"].items():
            invocations = check.get("shader_invocations")
            covered = max(check["coverage"] * REFERENCE_SIZE[0] * REFERENCE_SIZE[1], 1)
            per_pixel = "-" if invocations is None else f"{invocations / covered:.2f}"
            changed = max(check["covered"], 1)
            rows.append([scene, label, f"{100 * check['coverage']:.2f}", f"{100 * check['coverage_agreement']:.3f}",
                         per_pixel, f"{check['colour_changed']} ({100 * check['colour_changed'] / changed:.2f} %)",
                         f"{check['depth_changed']}",
                         f"{check['depth_error_p99']:.2e}", f"{check['depth_error_max']:.2e}",
                         f"{check['colour_error_p99']:.4f}" if "colour_error_p99" in check else "-"])
    lines += [] if not rows else [f"At {REFERENCE_SIZE[0]} x {REFERENCE_SIZE[1]}: fragment shader runs (every pass), pixels "
              f"changed against '{base}' (colour by more than 1/255; depth at all), and against the CPU reference "
              "(same quality)",
              table(["scene", "config", "coverage %", "coverage agrees %", "shader runs / covered px",
                     f"colour changed vs '{base}'", "depth changed", "depth err p99", "depth err max",
                     "colour err p99"], rows), ""]
    for scene, naive in result.get("naive", {}).items():
        for size, entry in naive.items():
            drawn, count = entry["strips"]
            how = "one draw" if count == 1 else f"{count} strips" if drawn == count else \
                f"projected from {drawn} of {count} strips"
            agreement = entry.get("coverage_agreement")
            lines.append(f"naive full-screen raymarch, {scene}, {size}: {entry['ms']:.1f} ms per frame ({how}; "
                         f"{entry['wall_ms']:.0f} ms wall clock)"
                         + (f"; {100 * entry['coverage']:.2f} % of pixels hit, {entry['steps_per_pixel']:.1f} steps of "
                            f"all {result['scenes'][scene]['boxes']} boxes per pixel" if "coverage" in entry else "")
                         + (f"; coverage agrees with the boxed reference on {100 * agreement:.2f} %"
                            if agreement is not None else "")
                         + (f"; GL error {entry['gl_error']:#x}" if entry["gl_error"] else ""))
    medians = [t["median_ms"] for entry in result["scenes"].values() for sizes in entry["times"].values()
               for t in sizes.values() if len(t["median_ms"]) > 1]
    spreads = [(max(m) - min(m)) / min(m) for m in medians]
    if spreads:
        lines.append(f"spread between the two passes: median {100 * np.median(spreads):.1f} %, "
                     f"worst {100 * max(spreads):.1f} %")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path, help="folder written by bench/gpu_frame_data.py")
    parser.add_argument("--sizes", default="960x540,1920x1080")
    parser.add_argument("--naive-sizes", default="120x68,960x540,1920x1080",
                        help="the same view at these sizes, empty: no naive frame")
    parser.add_argument("--scenes", default="", help="comma-separated file stems (default: every .npz)")
    parser.add_argument("--passes", type=int, default=2)
    parser.add_argument("--set", default="passes", choices=sorted(CONFIG_SETS),
                        help="passes: the preview's passes, today against what it draws; declaration: the "
                             "depth declaration, order and quality in one pass, and diagnostics")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    egl_context()
    result = {"renderer": GL.glGetString(GL.GL_RENDERER).decode(), "version": GL.glGetString(GL.GL_VERSION).decode(),
              "set": args.set, "configs": [label for label, _ in CONFIG_SETS[args.set]], "scenes": {}, "naive": {}}
    print(result["renderer"], "|", result["version"], flush=True)
    wanted = [s for s in args.scenes.split(",") if s]
    for path in sorted(args.data.glob("*.npz")):
        if wanted and path.stem not in wanted:
            continue
        data = dict(np.load(path))
        name = str(data["info"][0])
        sizes = parse_sizes(args.sizes)
        times, checks = measure_scene(data, sizes, args.passes, CONFIG_SETS[args.set])
        result["scenes"][name] = {"boxes": int(data["info"][2]), "sdf": str(data["info"][1]), "times": times,
                                  "checks": checks,
                                  "layers": {f"{w}x{h}": float(data[f"layers_{w}x{h}"]) for w, h in sizes},
                                  "shipped": {f"{w}x{h}": shipped_label(data, f"{w}x{h}") for w, h in sizes
                                              if args.set == "passes"}}
        print(f"{name}: done", flush=True)
        if args.json:
            args.json.write_text(json.dumps(result, indent=1, allow_nan=False))
        if name == "cloud" and args.naive_sizes:
            result["naive"][name] = measure_naive(data, parse_sizes(args.naive_sizes))
    if args.json:
        args.json.write_text(json.dumps(result, indent=1, allow_nan=False))
    print(report(result))


if __name__ == "__main__":
    main()

"""Accuracy against run time: writes docs/ACCURACY.md and its PNG plots (docs/accuracy_*.png).

    PYTHONPATH=addon python3 -m bench.bench_accuracy [--quick]

Sections (each measured here, from NumPy box scenes, with the native core; no Blender needed):

* encoding: decoded-origin error of FLOAT_COLOR, BYTE_COLOR (our quantisation-aware 8-bit and
  plain rounding of the same offsets) and 16-bit half floats (numpy float16 of the stored
  values, as engines store vertex data under vertex compression), for box sizes 0.01..1000 and
  distances from the object origin up to 10,000, beside the bake time of each mode;
* frame: angle between the baked axes and the box's true face normals under vertex noise, and
  which face gives axis 2 for faces nearly angle_epsilon apart;
* raymarch: hit error of the preview's sphere tracer (the CPU reference, core.raymarch) against
  the closed-form sphere, by max steps, epsilon and relaxation, with the average steps per ray;
* scaling: time and peak memory of the bake and the submesh tools from 1,000 to 1,000,000 boxes
  (log-log, fitted slopes).

Truth never comes from the bake: box centres and axes are the generator's; the origin a decode
is compared with is the bounds centre of the stored float32 vertices, computed here in float64.
--quick uses fewer boxes (for a smoke run); the committed page comes from a full run.
"""
from __future__ import annotations

import argparse
import ctypes
import datetime
import os
import pathlib
import json
import platform
import subprocess
import sys
import time

import numpy as np

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from boxmarch import core, scenes  # noqa: E402
from boxmarch.formats import layouts
from bench.common import best_of, reset_peak_rss, rss_bytes, table  # noqa: E402
from bench import bench_gpu_cost  # noqa: E402
from bench import bench_skinning  # noqa: E402

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"
SIZES = [0.01, 0.1, 1.0, 10.0, 100.0, 1000.0]
DISTANCES = [0.0, 10.0, 100.0, 1000.0, 10000.0]
USABLE = 0.01  # a decode error up to 1% of the half-extent counts as usable for raymarching


# -------------------------------------------------------------------------------------------------
# Shared maths (float64, independent of the bake)


def quat_matrices(q):
    """(n, 3, 3) frames (columns = local axes) of quaternions (x, y, z, w), normalised in float64."""
    q = np.asarray(q, np.float64)
    return layouts.quaternion_matrices(q / np.linalg.norm(q, axis=1, keepdims=True))


def box_truth(positions, quaternions):
    """Per box of 8 stored vertices: the bounds centre in the baked frame (float64, relative to
    the first vertex) and the largest local half-extent."""
    p = positions.astype(np.float64).reshape(-1, 8, 3)
    frames = quat_matrices(quaternions)
    local = np.einsum("nvi,nij->nvj", p - p[:, :1], frames)
    lo, hi = local.min(1), local.max(1)
    centre = p[:, 0] + np.einsum("nij,nj->ni", frames, 0.5 * (lo + hi))
    return centre, 0.5 * (hi - lo).max(1)


def relative_errors(positions, colours, quaternions, centre, half):
    """Per box: worst |decoded origin - centre| over its 8 vertices / its largest half-extent.
    colours (8n, 4) as stored, quaternions (n, 4) as stored."""
    f = core.decode_offsets(colours).reshape(-1, 8, 3)
    q = np.repeat(np.asarray(quaternions)[:, None, :], 8, axis=1)
    decoded = positions.astype(np.float64).reshape(-1, 8, 3) + core.rotate_vector(f, q)
    return np.linalg.norm(decoded - centre[:, None, :], axis=2).max(1) / half


def plain_bytes(colours_float):
    """Plain rounding of the float encoding to bytes: alpha byte = round(255 s) clamped to 1..255,
    rgb = round(255 (0.5 + 0.5 a f)) clamped, f taken from the float encoding."""
    f = core.decode_offsets(colours_float)
    s = colours_float[:, 3].astype(np.float64)
    alpha = np.clip(np.rint(255.0 * s), 1, 255)
    rgb = np.clip(np.rint(255.0 * (0.5 + 0.5 * (alpha / 255.0)[:, None] * f)), 0, 255)
    return np.c_[rgb, alpha].astype(np.uint8)


def boxes(rng, n, size, distance):
    """n boxes whose largest side is `size` (the others 0.3..1 of it), random rotations, centres
    `distance` from the object origin in random directions."""
    sizes = size * np.c_[np.ones(n), rng.uniform(0.3, 1.0, (n, 2))]
    rotations = scenes.random_rotations(n, rng)
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return scenes.box_arrays(directions * distance, sizes, rotations), sizes, rotations


# -------------------------------------------------------------------------------------------------
# Encoding


def encoding_sweep(n):
    rng = np.random.default_rng(1)
    rows, curves = [], {}
    for size in SIZES:
        for distance in DISTANCES:
            arrays, _, _ = boxes(rng, n, size, distance)
            positions = arrays[0]
            r_float = core.bake(*arrays)
            r_byte = core.bake(*arrays, encoding="BYTE_COLOR")
            np.testing.assert_array_equal(r_float.quaternions, r_byte.quaternions)
            centre, half = box_truth(positions, r_float.quaternions)
            q16 = r_float.quaternions.astype(np.float16).astype(np.float32)
            errors = {
                "float": relative_errors(positions, r_float.offsets, r_float.quaternions, centre, half),
                "8-bit (ours)": relative_errors(positions, r_byte.offsets, r_byte.quaternions, centre, half),
                "8-bit (plain rounding)": relative_errors(positions, plain_bytes(r_float.offsets),
                                                          r_float.quaternions, centre, half),
                "half (colour)": relative_errors(positions, r_float.offsets.astype(np.float16),
                                                 r_float.quaternions, centre, half),
                "half (colour + UV)": relative_errors(positions, r_float.offsets.astype(np.float16), q16, centre, half),
            }
            for name, e in errors.items():
                assert np.all(np.isfinite(e)), (name, size, distance)
                curves.setdefault(name, {}).setdefault(distance, []).append((size, e.max(), np.median(e)))
            rows.append([f"{size:g}", f"{distance:g}"] +
                        [f"{errors[k].max():.1e} / {np.median(errors[k]):.1e}" for k in errors])
    return list(errors), rows, curves


def encoding_times(n):
    rng = np.random.default_rng(2)
    arrays, _, _ = boxes(rng, n, 1.0, 100.0)
    t_float = best_of(3, lambda: core.bake(*arrays))
    t_byte = best_of(3, lambda: core.bake(*arrays, encoding="BYTE_COLOR"))
    offsets = core.bake(*arrays).offsets
    t_half = best_of(3, lambda: offsets.astype(np.float16))
    t_plain = best_of(3, lambda: plain_bytes(offsets))
    return [
        ["FLOAT_COLOR", f"{t_float * 1e3:.1f}", "-"],
        ["BYTE_COLOR (ours, quantisation-aware)", f"{t_byte * 1e3:.1f}", f"{(t_byte / t_float - 1) * 100:+.0f}%"],
        ["8-bit plain rounding (float bake + NumPy rounding)", f"{(t_float + t_plain) * 1e3:.1f}",
         f"{t_plain / t_float * 100:+.0f}%"],
        ["half float (float bake + float16 conversion)", f"{(t_float + t_half) * 1e3:.1f}",
         f"{t_half / t_float * 100:+.0f}%"],
    ]


def usable_ranges(curves, name):
    """Sizes at which the worst error over all distances stays within USABLE."""
    ok = []
    for size in SIZES:
        worst = max(e for d in curves[name].values() for s, e, _ in d if s == size)
        if worst <= USABLE:
            ok.append(size)
    return ok


def plot_encoding(names, curves, path):
    fig, grid = plt.subplots(2, 3, figsize=(12, 7), sharey=True)
    axes = grid.ravel()
    for ax, name in zip(axes, names):
        for distance, points in sorted(curves[name].items()):
            s, worst, median = map(np.array, zip(*points))
            line, = ax.loglog(s, worst, "o-", label=f"d={distance:g}")
            ax.loglog(s, median, ":", color=line.get_color())
        ax.set_title(name)
    # Last panel: the two 8-bit encodings side by side, worst over every distance.
    ax = axes[len(names)]
    for name, style in (("8-bit (ours)", "o-"), ("8-bit (plain rounding)", "s--")):
        worst = [max(e for d in curves[name].values() for s, e, _ in d if s == size) for size in SIZES]
        median = [np.median([m for d in curves[name].values() for s, _, m in d if s == size]) for size in SIZES]
        line, = ax.loglog(SIZES, worst, style, label=f"{name}, max")
        ax.loglog(SIZES, median, ":", color=line.get_color(), label=f"{name}, median")
    ax.set_title("8-bit: ours against plain rounding")
    ax.legend(fontsize=7)
    for ax in axes:
        ax.axhline(USABLE, color="grey", lw=0.8, ls="--")
        ax.set_xlabel("box size (units)")
        ax.grid(True, which="major", alpha=0.3)
    for row in grid:
        row[0].set_ylabel("decode error / half-extent\n(solid: max, dotted: median)")
    axes[0].legend(fontsize=7, title="distance", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# -------------------------------------------------------------------------------------------------
# Frames


def distinct_boxes(rng, n):
    """Boxes whose sides differ pairwise by a factor >= 1.15 (no face-area ties), largest 1."""
    ratios = rng.uniform(1.15, 2.0, (n, 2))
    sizes = np.c_[np.ones(n), 1 / ratios[:, 0], 1 / ratios[:, 0] / ratios[:, 1]]
    return rng.permuted(sizes, axis=1)


def frame_noise(n):
    rng = np.random.default_rng(3)
    rows, points = [], []
    for noise in [0.0, 1e-5, 1e-4, 1e-3, 3e-3, 1e-2]:
        sizes = distinct_boxes(rng, n)
        rotations = scenes.random_rotations(n, rng)
        arrays = list(scenes.box_arrays(rng.uniform(-50, 50, (n, 3)), sizes, rotations))
        jitter = rng.uniform(-noise, noise, arrays[0].shape)  # box size is 1: noise is a fraction of it
        arrays[0] = (arrays[0] + jitter).astype(np.float32)
        start = time.perf_counter()
        r = core.bake(*arrays)
        elapsed = time.perf_counter() - start
        frames = quat_matrices(r.quaternions)
        # Angle of each baked axis to the nearest true axis line (a face normal of the box).
        cosines = np.abs(np.einsum("nik,nij->nkj", frames, rotations)).max(2)
        angles = np.degrees(np.arccos(np.clip(cosines, 0, 1))).max(1)
        centre, half = box_truth(arrays[0], r.quaternions)
        decode_error = relative_errors(arrays[0], r.offsets, r.quaternions, centre, half).max()
        rows.append([f"{noise * 100:g}%", f"{np.median(angles):.2e}", f"{angles.max():.2e}",
                     f"{decode_error:.1e}", f"{r.degenerate}", f"{elapsed * 1e3:.1f}"])
        points.append((noise, np.median(angles), angles.max()))
    return rows, points


def prism(tilt):
    """Prism (width 4, height 1, depth 1.5) whose top edge is tilted by `tilt` rad: the slanted
    top face is the largest; the bottom face is `tilt` off it and the second largest."""
    width, height, depth = 4.0, 1.0, 1.5
    quad = np.array([[0, 0], [width, 0], [width, height + width * np.tan(tilt)], [0, height]])
    points = np.vstack([np.c_[quad, np.zeros(4)], np.c_[quad, np.full(4, depth)]])
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    corner_verts = np.array([v for f in faces for v in f], np.int32)
    return (points.astype(np.float32), np.zeros((0, 2), np.int32), np.arange(0, 24, 4, dtype=np.int32),
            np.full(6, 4, np.int32), corner_verts)


def frame_epsilon(copies):
    """Tilted prisms around angle_epsilon = 0.1 rad, each copied with 0.1% vertex noise: how often
    axis 2 comes from the bottom face (tilt above epsilon) rather than the end caps."""
    rng = np.random.default_rng(4)
    rows = []
    epsilon = 0.1
    for ratio in [0.9, 0.99, 0.995, 0.999, 1.001, 1.005, 1.01, 1.1]:
        base = prism(epsilon * ratio)
        n = copies
        positions = np.tile(base[0], (n, 1)) + rng.uniform(-1e-3, 1e-3, (8 * n, 3)).astype(np.float32)
        corner_verts = (base[4][None] + 8 * np.arange(n)[:, None]).reshape(-1).astype(np.int32)
        arrays = (positions.astype(np.float32), base[1], np.arange(0, 24 * n, 4, dtype=np.int32),
                  np.full(6 * n, 4, np.int32), corner_verts)
        r = core.bake(*arrays, angle_epsilon=epsilon)
        axis2 = quat_matrices(r.quaternions)[:, :, 1]
        from_caps = np.abs(axis2[:, 2]) > 0.99  # cap normals are +-z
        exact = core.bake(*base, angle_epsilon=epsilon)
        exact_axis2 = quat_matrices(exact.quaternions)[0][:, 1]
        rows.append([f"{ratio:g}", f"{epsilon * ratio:.4f}",
                     "end cap (z)" if abs(exact_axis2[2]) > 0.99 else "bottom face, made orthogonal",
                     f"{100 * (1 - from_caps.mean()):.0f}%"])
    return rows


def plot_frames(points, path):
    noise, median, worst = map(np.array, zip(*points))
    x = np.maximum(noise * 100, 1e-4)
    fig, ax = plt.subplots(figsize=(5, 3.6))
    ax.loglog(x, np.maximum(worst, 1e-8), "o-", label="max")
    ax.loglog(x, np.maximum(median, 1e-8), "s:", label="median")
    ax.set_xlabel("vertex noise (% of box size; 0 plotted at 1e-4)")
    ax.set_ylabel("axis error (degrees)")
    ax.set_title("Frame error under vertex noise")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -------------------------------------------------------------------------------------------------
# Raymarch


def sphere_rays(n, rng, half):
    """Rays from random points 3 half-extents out towards random points of the box |p| <= half
    (every incidence angle, grazing ones included), and where each hits the preset SPHERE
    (radius = smallest half-extent) in closed form: t (inf on a miss)."""
    directions = rng.normal(size=(n, 3))
    origins = 3.0 * half.max() * directions / np.linalg.norm(directions, axis=1, keepdims=True)
    targets = rng.uniform(-1.0, 1.0, (n, 3)) * half
    d = targets - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    radius = half.min()
    b = np.sum(origins * d, axis=1)
    disc = b * b - (np.sum(origins * origins, axis=1) - radius * radius)
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
    return origins.astype(np.float32), d.astype(np.float32), t


def march_errors(origins, directions, t_true, half, **options):
    """Hit-position error / smallest half-extent over rays that truly hit, false misses and
    false hits, and the mean steps per ray, for core.raymarch with these options."""
    r = core.raymarch(origins, directions, half, sdf="SPHERE", threads=0, **options)
    truth_hit = np.isfinite(t_true)
    true_points = origins.astype(np.float64) + directions.astype(np.float64) * np.where(truth_hit, t_true, 0)[:, None]
    both = truth_hit & r.hit
    err = np.linalg.norm(r.positions.astype(np.float64)[both] - true_points[both], axis=1) / half.min()
    return dict(median=np.median(err) if err.size else np.nan, max=err.max() if err.size else np.nan,
                p99=np.percentile(err, 99) if err.size else np.nan,
                false_miss=np.mean(truth_hit & ~r.hit) / max(np.mean(truth_hit), 1e-12),
                false_hit=np.mean(~truth_hit & r.hit), steps=r.steps.mean())


def raymarch_sweep(n):
    rng = np.random.default_rng(6)
    half = np.array([1.0, 1.0, 1.0], np.float32)
    origins, directions, t_true = sphere_rays(n, rng, half)
    defaults = dict(max_steps=64, epsilon=1e-3, relaxation=1.0)
    default = march_errors(origins, directions, t_true, half, **defaults)
    step_rows, step_points = [], []
    for epsilon in [1e-2, 1e-3, 1e-4, 1e-5]:
        for max_steps in [8, 16, 32, 64, 128, 256]:
            e = march_errors(origins, directions, t_true, half, max_steps=max_steps, epsilon=epsilon, relaxation=1.0)
            step_rows.append([f"{epsilon:g}", f"{max_steps}", f"{e['median']:.1e}", f"{e['p99']:.1e}", f"{e['max']:.1e}",
                              f"{100 * e['false_miss']:.2f}%", f"{100 * e['false_hit']:.2f}%", f"{e['steps']:.1f}"])
            step_points.append((epsilon, max_steps, e))
    relax_rows, relax_points = [], []
    for relaxation in [0.5, 0.6, 0.7, 0.8, 0.9, 1.0]:
        for max_steps in [32, 64, 128]:
            e = march_errors(origins, directions, t_true, half, max_steps=max_steps, epsilon=1e-3, relaxation=relaxation)
            relax_rows.append([f"{relaxation:g}", f"{max_steps}", f"{e['median']:.1e}", f"{e['max']:.1e}",
                               f"{100 * e['false_miss']:.2f}%", f"{e['steps']:.1f}"])
            relax_points.append((relaxation, max_steps, e))
    start = time.perf_counter()
    core.raymarch(origins, directions, half, sdf="SPHERE", **defaults)
    elapsed = time.perf_counter() - start
    return default, step_rows, step_points, relax_rows, relax_points, elapsed


def plot_raymarch(step_points, relax_points, path):
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(13, 3.8))
    for epsilon in sorted({p[0] for p in step_points}, reverse=True):
        pts = [(e["steps"], e["median"], e["max"], e["false_miss"], m) for eps, m, e in step_points if eps == epsilon]
        steps, median, worst, miss, labels = zip(*pts)
        line, = a.loglog(steps, median, "o-", label=f"epsilon={epsilon:g}")
        a.loglog(steps, worst, "^--", color=line.get_color(), alpha=0.6)
        b.semilogy(steps, np.maximum(np.array(miss) * 100, 1e-3), "o-", color=line.get_color(), label=f"epsilon={epsilon:g}")
        for x, y, m in zip(steps, np.maximum(np.array(miss) * 100, 1e-3), labels):
            b.annotate(str(m), (x, y), fontsize=6, textcoords="offset points", xytext=(2, 2))
    a.set_xlabel("average steps per ray")
    a.set_ylabel("hit error / radius (o median, ^ max)")
    a.set_title("SPHERE preset, relaxation 1")
    a.legend(fontsize=7)
    a.grid(True, alpha=0.3)
    b.set_xlabel("average steps per ray (labels: max_steps)")
    b.set_ylabel("false misses, % of true hits (0 drawn at 1e-3)")
    b.set_title("Misses from running out of steps")
    b.legend(fontsize=7)
    b.grid(True, alpha=0.3)
    for max_steps in sorted({p[1] for p in relax_points}):
        relax, steps = zip(*[(r, e["steps"]) for r, m, e in relax_points if m == max_steps])
        c.plot(relax, steps, "o-", label=f"max_steps={max_steps}")
    c.set_xlabel("relaxation")
    c.set_ylabel("average steps per ray")
    c.set_title("epsilon 1e-3")
    c.legend(fontsize=7)
    c.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -------------------------------------------------------------------------------------------------
# Scaling


def tool_runs(arrays):
    """The operations whose scaling is measured, each a function of no arguments over the same
    scene: the bake and the submesh tools (issue 3) at their operator defaults, except that UVs
    are packed without padding (the default 0.002 leaves no room for 600,000 islands)."""
    positions, edges, face_starts, face_sizes, corner_verts = arrays
    ids, count = core.find_submeshes(*arrays)
    selected = np.zeros(len(positions), np.uint8)
    selected[::100] = 1
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    corner_uv = np.tile(square, (len(face_starts), 1))  # every face its own island
    height = np.ascontiguousarray(positions[:, 2])
    return {
        "bake": lambda: core.bake(*arrays),
        "select linked across": lambda: core.select_linked_across(positions, selected, ids, count, epsilon=1e-4),
        "find duplicates": lambda: core.find_duplicate_submeshes(positions, ids, count, tolerance=1e-4),
        "merge by distance": lambda: core.merge_targets(positions, ids, count, distance=1e-3),
        "pack UVs by height": lambda: core.pack_uv_by_height(corner_uv.copy(), *arrays, vertex_height=height,
                                                             submesh_of_vertex=ids, submesh_count=count,
                                                             padding=0.0),
    }


TOOLS = ["bake", "select linked across", "find duplicates", "merge by distance", "pack UVs by height"]


def scaling_child(n, tool):
    """One measurement in a fresh process (so freed memory of earlier work cannot hide the peak):
    the peak resident-set rise of a first run of `tool` on n boxes, then the best wall and CPU
    time of further runs. Prints JSON."""
    arrays, _, _, _ = scenes.random_boxes(n, seed=5)
    run = tool_runs(arrays)[tool]
    # Memory first, with the scene's freed temporaries returned to the system: memory the
    # allocator keeps from earlier work would otherwise be reused unseen and hide the peak.
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    base = rss_bytes()
    reset_peak_rss()
    result = run()
    peak = rss_bytes("VmHWM") - base
    del result
    repeats = 3 if n <= 316_228 else 2
    wall, cpu = float("inf"), float("inf")
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        run()
        wall, cpu = min(wall, time.perf_counter() - w0), min(cpu, time.process_time() - c0)
    print(json.dumps(dict(n=n, wall=wall, cpu=cpu, peak=peak, inputs=sum(a.nbytes for a in arrays)), allow_nan=False))


def scaling(counts):
    """Per tool: table rows, points (n, wall, cpu, peak) and fitted log-log slopes."""
    rows, points, slopes = [], {}, {}
    for tool in TOOLS:
        for n in counts:
            child = subprocess.run([sys.executable, os.path.abspath(__file__), "--scaling-child", str(n), tool],
                                   capture_output=True, text=True, check=True)
            m = json.loads(child.stdout.strip().splitlines()[-1])
            rows.append([tool, f"{n:,}", f"{m['wall'] * 1e3:.1f}", f"{m['cpu'] * 1e3:.1f}", f"{m['cpu'] / n * 1e9:.0f}",
                         f"{m['peak'] / 2**20:.1f}", f"{m['peak'] / n:.0f}"])
            points.setdefault(tool, []).append((n, m["wall"], m["cpu"], m["peak"]))
        n, wall, cpu, peak = map(np.array, zip(*points[tool]))
        big = n >= 10_000
        slopes[tool] = {name: np.polyfit(np.log(n[big]), np.log(np.maximum(v[big], 1e-9)), 1)[0]
                        for name, v in (("wall", wall), ("cpu", cpu), ("memory", peak))}
        print(f"scaling {tool} done", file=sys.stderr, flush=True)
    return rows, points, slopes


def plot_scaling(points, slopes, path):
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    for tool in TOOLS:
        n, wall, cpu, peak = map(np.array, zip(*points[tool]))
        line, = a.loglog(n, cpu, "o-", label=f"{tool} (slope {slopes[tool]['cpu']:.2f})")
        b.loglog(n, np.maximum(peak, 1) / 2**20, "o-", color=line.get_color(),
                 label=f"{tool} (slope {slopes[tool]['memory']:.2f})")
    n = np.array([p[0] for p in points["bake"]])
    cpu = np.array([p[2] for p in points["bake"]])
    a.loglog(n, cpu[-1] * n / n[-1], "k:", lw=0.8, label="slope 1")
    a.set_xlabel("boxes")
    a.set_ylabel("CPU time, all threads (s)")
    a.legend(fontsize=7)
    a.grid(True, alpha=0.3)
    b.set_xlabel("boxes")
    b.set_ylabel("peak extra memory (MiB)")
    b.legend(fontsize=7)
    b.grid(True, alpha=0.3)
    fig.suptitle("Scaling of the bake and the submesh tools (boxmarch.core)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -------------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer boxes: a smoke run, not for the docs")
    parser.add_argument("--out", default=str(DOCS), help="directory for ACCURACY.md and the plots")
    parser.add_argument("--scaling-child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.scaling_child:
        return scaling_child(int(args.scaling_child[0]), args.scaling_child[1])
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    quick = args.quick
    n_cell = 50 if quick else 400
    counts = [1000, 10_000, 100_000] if quick else [1000, 3162, 10_000, 31_623, 100_000, 316_228, 1_000_000]

    names, enc_rows, curves = encoding_sweep(n_cell)
    print("encoding done", file=sys.stderr, flush=True)
    time_rows = encoding_times(20_000 if quick else 100_000)
    plot_encoding(names, curves, out / "accuracy_encoding.png")
    noise_rows, noise_points = frame_noise(500 if quick else 5000)
    plot_frames(noise_points, out / "accuracy_frame.png")
    eps_rows = frame_epsilon(200 if quick else 2000)
    print("frames done", file=sys.stderr, flush=True)
    ray_default, step_rows, step_points, relax_rows, relax_points, ray_time = raymarch_sweep(20_000 if quick else 200_000)
    plot_raymarch(step_points, relax_points, out / "accuracy_raymarch.png")
    print("raymarch done", file=sys.stderr, flush=True)
    scale_rows, scale_points, slopes = scaling(counts)
    plot_scaling(scale_points, slopes, out / "accuracy_scaling.png")

    worst = {k: max(e for d in curves[k].values() for _, e, _ in d) for k in names}
    # 8-bit where it is meant to be used (sizes 1..100): worst and median-of-medians, ours vs plain
    in_range = {k: [(e, m) for d in curves[k].values() for s, e, m in d if 1.0 <= s <= 100.0]
                for k in ("8-bit (ours)", "8-bit (plain rounding)")}
    byte_worst = {k: max(e for e, _ in v) for k, v in in_range.items()}
    byte_median = {k: float(np.median([m for _, m in v])) for k, v in in_range.items()}
    usable = {k: usable_ranges(curves, k) for k in names}

    def sizes_text(sizes):
        return ", ".join(f"{s:g}" for s in sizes) if sizes else "none"

    page = f"""# Accuracy against run time

Measured by `PYTHONPATH=addon python3 -m bench.bench_accuracy` (one command: it writes this page
and its plots). {datetime.date.today().isoformat()}, {platform.machine()}, {os.cpu_count()} cores,
no GPU; times are the best of several runs on a shared machine.

Errors are measured against truth computed outside the bake: the origin a decode must land on is
the bounds centre of the stored float32 vertices in the baked frame, computed in float64; the true
axes are the generator's rotations. "Error" is |decoded origin - true origin| / largest
half-extent, worst over the 8 vertices of a box (the decode is linear, so vertices bound every
interior point).

## Headlines

* Worst decode error over every size 0.01..1000 and distance 0..10,000:
  FLOAT_COLOR **{worst["float"]:.1e}**, BYTE_COLOR (ours) **{worst["8-bit (ours)"]:.1e}**,
  8-bit plain rounding {worst["8-bit (plain rounding)"]:.1e}, half-float colour {worst["half (colour)"]:.1e}.
* 8-bit for boxes of 1..100 units: worst {byte_worst["8-bit (ours)"]:.1e} (median {byte_median["8-bit (ours)"]:.1e})
  with our quantisation-aware encoding against {byte_worst["8-bit (plain rounding)"]:.1e}
  (median {byte_median["8-bit (plain rounding)"]:.1e}) with plain rounding.
* Usable (worst error <= {USABLE:.0%} of the half-extent at every distance), by box size:
  float {sizes_text(usable["float"])}; 8-bit ours {sizes_text(usable["8-bit (ours)"])};
  8-bit plain {sizes_text(usable["8-bit (plain rounding)"])}; half colour {sizes_text(usable["half (colour)"])};
  half colour + UV {sizes_text(usable["half (colour + UV)"])}.
* Raymarch at the preview's defaults (64 steps, epsilon 1e-3, relaxation 1), SPHERE preset:
  hit error median **{ray_default["median"]:.1e}**, max **{ray_default["max"]:.1e}** of the radius;
  {100 * ray_default["false_miss"]:.2f}% of true hits missed; {ray_default["steps"]:.1f} steps per ray on average.
* Bake time scales with slope **{slopes["bake"]["cpu"]:.2f}** in CPU time ({slopes["bake"]["wall"]:.2f} wall) (log-log,
  10,000..{counts[-1]:,} boxes); peak memory slope {slopes["bake"]["memory"]:.2f}. Submesh tools (CPU time slope):
  {", ".join(f"{t} {slopes[t]['cpu']:.2f}" for t in TOOLS[1:])}.

## Encoding error by box size and distance

Each cell: max / median over {n_cell} boxes (largest side = size, the other two 0.3..1 of it,
random rotations, centres at the distance from the object origin in random directions).
*8-bit (plain rounding)* rounds the float encoding's values to bytes (alpha = round(255 s),
clamped to 1..255) — what a naive converter does; *ours* searches the 32 largest alphas that fit
and keeps the one whose rounded bytes decode best. *half* stores the float colour (and, in the
last column, the quaternion UVs too) as IEEE float16, as engines do under vertex compression.

{table(["size", "distance"] + names, enc_rows)}

![Decode error against box size, one line per distance](accuracy_encoding.png)

Reading it: float is exact to float32 rounding everywhere. 8-bit has a fixed step of
2 / (255 a) units with alpha a <= 1, so boxes below about 1 unit lose relative precision (the
step is a fixed fraction of a unit) and boxes above 255 units cannot fit a * |f| <= 1 with
a >= 1/255. Half floats carry 11 significant bits: about 1e-3 of the half-extent, independent of
size, until the quaternion is stored in half precision too, which adds a rotation error of the
same order.

Bake time of each mode ({"20,000" if quick else "100,000"} boxes, 1 unit, 100 units out):

{table(["mode", "ms", "vs float"], time_rows)}

## Frame error

### Under vertex noise

Boxes with sides differing by a factor >= 1.15 (no face-area ties), largest side 1, every vertex
coordinate moved uniformly by up to the noise: angle between each baked axis and the nearest
true face normal (worst of the three axes), in degrees. The decode stays exact regardless: it is
measured against the noisy vertices the bake sees.

{table(["noise", "median angle (deg)", "max angle (deg)", "decode error", "degenerate", "bake ms"], noise_rows)}

![Axis error against vertex noise](accuracy_frame.png)

### Faces nearly angle_epsilon apart

A prism whose largest face (the slanted top) and second-largest face (the bottom) are `tilt`
apart, angle_epsilon = 0.1 rad. Below epsilon the bottom face is too close to the top's
direction, so axis 2 comes from the end caps; above it, from the bottom face (made orthogonal to
axis 1): the frame turns by 90 degrees about axis 1 as the tilt crosses epsilon. The last column
is the share of copies with 0.1% vertex noise that take the bottom face: the switch is as sharp
as the noise allows, and an artist who needs one behaviour sets angle_epsilon away from the
shape's angles.

{table(["tilt / epsilon", "tilt (rad)", "axis 2 (noise-free)", "noisy copies using the bottom face"], eps_rows)}

## Raymarch error

The preview's sphere tracer, run by the CPU reference raymarcher (`core.raymarch`, the same
arithmetic as the viewport shader), on the SPHERE preset of a box with half-extents 1 (radius 1),
against the closed-form ray-sphere intersection. {"20,000" if quick else "200,000"} rays start 3 units out in
random directions and aim at random points of the box, so every incidence angle occurs, grazing
ones included (those need the most steps). Error = |march hit - true hit| / radius over rays
that truly hit and were hit; a *false miss* is a true hit the march gave up on (steps spent
before the distance fell below epsilon); a *false hit* is a hit where the sphere is missed
(closer than epsilon to its silhouette). Steps are SDF evaluations per ray, averaged over all
rays (misses of the box take 0).

Against max_steps and epsilon (relaxation 1):

{table(["epsilon", "max_steps", "median error", "99th pct", "max error", "false misses", "false hits", "avg steps"], step_rows)}

Against relaxation (epsilon 1e-3): below 1 each step goes only that share of the safe distance,
which guards SDFs that overestimate (smooth unions, repetition) but costs steps:

{table(["relaxation", "max_steps", "median error", "max error", "false misses", "avg steps"], relax_rows)}

![Hit error and false misses against average steps; steps against relaxation](accuracy_raymarch.png)

The median error tracks epsilon (about 0.75 epsilon: the march stops once the distance falls
below it); the maximum is set by grazing rays, which pass within epsilon of the surface up to
sqrt(2 epsilon r) before the true hit (0.045 r at epsilon 1e-3), and raising max_steps beyond what
those rays need changes nothing.
The default settings march {"20,000" if quick else "200,000"} rays in {ray_time * 1e3:.0f} ms on this machine.

## Scaling

`core.bake` and the submesh tools of N random boxes (sizes 0.05..2, within 100 units, 8 vertices
each), default threads, every tool and N in a fresh process: *select linked across* from every
100th vertex with epsilon 1e-4, *find duplicates* with tolerance 1e-4, *merge by distance*
(`merge_targets`, 1e-3), *pack UVs by height* with every face its own island and no padding
(the default padding of 0.002 leaves no room for more than about 600,000 islands). Wall is the best of
2-3 runs; CPU is the process's CPU time over all threads (less sensitive to other load on the
shared machine, which was busy during the run: compare docs/BENCHMARKS.md for quiet-machine
times). Peak extra memory is the rise of the process's peak resident set during the first run
(inputs excluded, outputs included).

{table(["operation", "boxes", "wall ms", "CPU ms", "CPU ns per box", "peak extra MiB", "peak bytes per box"], scale_rows)}

![Time and peak memory against box count, log-log](accuracy_scaling.png)

Fitted log-log slopes over 10,000..{counts[-1]:,} boxes (1.0 is linear):

{table(["operation", "CPU time", "wall time", "memory"],
        [[t, *(f"{slopes[t][key]:.2f}" for key in ("cpu", "wall", "memory"))] for t in TOOLS])}
"""
    page += bench_skinning.accuracy_section()  # its plot: scripts/skinning_accuracy_plot.py
    page += bench_gpu_cost.accuracy_section()
    (out / "ACCURACY.md").write_text(page)
    print(page)


if __name__ == "__main__":
    main()

"""The closed-form hits of the presets (shaders/glsl/raymarch.glsl bm_preset_hit) run as the GPU
runs them, in a compute shader on Mesa's llvmpipe, against a float64 reference written here from
the presets' definitions (sdf.glsl's comments: the shapes, their sizes and axes), which sphere-traces
the exact SDF in float64 to 1e-12 of the box. Used by tests/test_closed_form.py and
bench/bench_closed_form.py.

Rays as a fragment casts them: from a random eye (1 to 10,000 box sizes away) at a random point of
the box, starting at the box's face (ro on the box, as the fragment's -f), or from an eye inside the
box but outside the shape; boxes of largest half-extent 0.01..1000, the other two 0.15..1 of it;
ro and rd rounded to float32 as the shader receives them, the reference fed the rounded values.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from boxmarch import core
from boxmarch.formats import shader_sources

ROOT = Path(__file__).resolve().parents[2]
PRESETS = core.SDF_PRESETS  # bm_sdf_by_id's numbering: 0 box ... 6 link


# ---- the presets in float64, from sdf.glsl's definitions
def _by_extent_order(h):
    """(N, 3) index arrays: the box's axes sorted by extent, a later axis moving ahead only when
    more than 0.1 % longer (sdf.glsl bm_by_extent's tie band), as three compare-and-swaps."""
    order = np.tile(np.arange(3), (len(h), 1))
    s = h.copy()
    for i, j in ((0, 1), (1, 2), (0, 1)):
        swap = s[:, j] > 1.001 * s[:, i]
        for a in (order, s):
            a[swap, i], a[swap, j] = a[swap, j], a[swap, i].copy()
    return order


def _sorted(v, order):
    return np.take_along_axis(v, order, 1)


def _length(v):
    return np.sqrt((v * v).sum(-1))


def preset_distance(shape, p, h):
    """Exact signed distance of preset number ``shape`` (one for all rows) sized by h, float64."""
    order = _by_extent_order(h)
    q, s = _sorted(p, order), _sorted(h, order)
    if shape == 0:
        d = np.abs(p) - h
        return _length(np.maximum(d, 0)) + np.minimum(d.max(-1), 0)
    if shape == 1:
        return _length(p) - h.min(-1)
    if shape == 2:
        r = 0.25 * h.min(-1)
        d = np.abs(p) - (h - r[:, None])
        return _length(np.maximum(d, 0)) + np.minimum(d.max(-1), 0) - r
    if shape == 3:  # along the longest axis, radius the smaller of the other two
        r = np.minimum(s[:, 1], s[:, 2])
        a = np.maximum(s[:, 0] - r, 0)
        x = q[:, 0] - np.clip(q[:, 0], -a, a)
        return np.sqrt(x * x + q[:, 1] ** 2 + q[:, 2] ** 2) - r
    if shape == 4:  # a rod along the longest axis, else a disc around the shortest
        rod = s[:, 0] * s[:, 2] > s[:, 1] ** 2
        axis = np.where(rod, 0, 2)
        across = np.where(rod[:, None], [1, 2], [0, 1])
        radius = np.minimum(np.take_along_axis(s, across, 1)[:, 0], np.take_along_axis(s, across, 1)[:, 1])
        radial = _length(np.take_along_axis(q, across, 1)) - radius
        along = np.abs(np.take_along_axis(q, axis[:, None], 1)[:, 0]) - np.take_along_axis(s, axis[:, None], 1)[:, 0]
        d = np.stack([radial, along], -1)
        return np.minimum(d.max(-1), 0) + _length(np.maximum(d, 0))
    if shape == 5:  # around the shortest axis, as wide as the middle one
        minor = np.minimum(s[:, 2], 0.5 * np.minimum(s[:, 0], s[:, 1]))
        major = np.minimum(s[:, 0], s[:, 1]) - minor
        return np.sqrt((_length(q[:, :2]) - major) ** 2 + q[:, 2] ** 2) - minor
    # link: stretched along the longest axis, the ring across the middle one
    thickness = np.minimum(s[:, 2], 0.25 * np.minimum(s[:, 0], s[:, 1]))
    half_length = np.maximum(s[:, 0] - s[:, 1], 0)
    ring = s[:, 1] - thickness
    along = np.maximum(np.abs(q[:, 0]) - half_length, 0)
    return np.sqrt((np.sqrt(along ** 2 + q[:, 1] ** 2) - ring) ** 2 + q[:, 2] ** 2) - thickness


def reference_hits(shape, ro, rd, h, iterations=4000):
    """(t, unit normal, resolved) of the first hit of each ray in float64: sphere tracing of the
    exact SDF to 1e-12 of the box's size; the normal by central differences of the SDF there.
    t = -1 for a miss (the ray leaves the box). resolved: False where the answer is ill-posed at
    float32 (a miss passing within 1e-5 of the box's size of the surface, a hit within 0.6 degrees
    of grazing, or no convergence): excluded from the comparison and counted."""
    ro, rd, h = (np.asarray(a, np.float64) for a in (ro, rd, h))
    rd = rd / _length(rd)[:, None]
    scale = h.max(-1)
    inv = 1.0 / np.where(np.abs(rd) < 1e-300, 1e-300, rd)
    t_exit = np.maximum((h - ro) * inv, (-h - ro) * inv).min(-1)
    t = np.zeros(len(ro))
    nearest = np.full(len(ro), np.inf)
    active = np.ones(len(ro), bool)
    hit = np.zeros(len(ro), bool)
    for _ in range(iterations):
        if not active.any():
            break
        idx = np.nonzero(active)[0]
        d = preset_distance(shape, ro[idx] + rd[idx] * t[idx, None], h[idx])
        nearest[idx] = np.minimum(nearest[idx], d)
        done = d < 1e-12 * scale[idx]
        hit[idx[done]] = True
        t[idx] += np.where(done, 0.0, d)
        active[idx[done | (t[idx] > t_exit[idx])]] = False
    p = ro + rd * t[:, None]
    e = 1e-7 * scale
    n = np.stack([preset_distance(shape, p + e[:, None] * axis, h) - preset_distance(shape, p - e[:, None] * axis, h)
                  for axis in np.eye(3)], -1)
    n /= np.maximum(_length(n), 1e-300)[:, None]
    resolved = ~active & np.where(hit, np.abs((n * rd).sum(-1)) > 0.01, nearest > 1e-5 * scale)
    return np.where(hit, t, -1.0), n, resolved


def random_rays(count, seed, from_eye_share=0.2):
    """(ro, rd, h) float32 and from_eye: rays as fragments cast them (module docstring);
    from_eye_share of them start at an eye inside the box (the caller keeps those outside the
    shape: a fragment whose eye lies inside it hits at 0 without solving)."""
    rng = np.random.default_rng(seed)
    largest = 10.0 ** rng.uniform(-2, 3, count)
    h = largest[:, None] * rng.uniform(0.15, 1.0, (count, 3))
    h[np.arange(count), rng.integers(0, 3, count)] = largest
    # cubes and ties within the tie band: the presets' axis rules at their edge
    tie = rng.random(count) < 0.1
    h[tie] = largest[tie, None] * rng.choice([1.0, 1.0005], (tie.sum(), 3))
    target = h * rng.uniform(-1, 1, (count, 3))
    direction = rng.normal(size=(count, 3))
    direction /= _length(direction)[:, None]
    eye = target + direction * (largest * 10.0 ** rng.uniform(0, 4, count))[:, None]
    rd = target - eye
    rd /= _length(rd)[:, None]
    inv = 1.0 / np.where(np.abs(rd) < 1e-300, 1e-300, rd)
    t_entry = np.minimum((h - eye) * inv, (-h - eye) * inv).max(-1)
    ro = eye + rd * t_entry[:, None]
    inside = rng.random(count) < from_eye_share
    ro[inside] = h[inside] * rng.uniform(-1, 1, (inside.sum(), 3))
    return ro.astype(np.float32), rd.astype(np.float32), h.astype(np.float32), inside


COMPUTE = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Rays { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer Hits { vec4 hits[]; };
uniform int count;
__LIBRARY__
float map(vec3 p) { return 1.0; }
void main()
{
  int i = int(gl_GlobalInvocationID.x);
  if (i >= count) return;
  vec4 a = rays[3 * i];
  vec4 b = rays[3 * i + 1];
  vec4 c = rays[3 * i + 2];
  hits[i] = __CALL__;
}
"""

GL_SIDE = """
import sys
import numpy as np
from bench.gl_headless import GL, compute_program, egl_context, storage_buffers
egl_context()
data = dict(np.load(sys.argv[1]))
program = compute_program(data["source"])
GL.glUseProgram(program)
count = len(data["rays"]) // 3
storage_buffers(data["rays"], count * 16)
GL.glUniform1i(GL.glGetUniformLocation(program, "count"), count)
GL.glDispatchCompute((count + 63) // 64, 1, 1)
GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
out = np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, count * 16), np.float32).reshape(count, 4)
np.save(sys.argv[2], out)
"""


def gpu_run(call: str, slots, library=None):
    """GLSL vec4 expression ``call`` of three vec4 a, b, c, each row of ``slots`` ((N, 3, 4)
    float32) giving them, run by llvmpipe in a compute shader after sdf.glsl and raymarch.glsl:
    (N, 4) float32. ``library``: the GLSL to run in place of those two (bench_closed_form's edit)."""
    library = library or shader_sources.read_glsl("sdf.glsl") + "\n" + shader_sources.read_glsl("raymarch.glsl")
    slots = np.ascontiguousarray(slots, np.float32)
    with tempfile.TemporaryDirectory() as tmp:
        source, result = Path(tmp) / "rays.npz", Path(tmp) / "hits.npy"
        np.savez(source, rays=slots.reshape(-1, 4), source=COMPUTE.replace("__LIBRARY__", library).replace("__CALL__", call))
        env = {**os.environ, "EGL_PLATFORM": "surfaceless", "PYTHONPATH": str(ROOT)}
        proc = subprocess.run([sys.executable, "-c", GL_SIDE, str(source), str(result)], env=env,
                              capture_output=True, text=True, timeout=300)
        if proc.returncode != 0:
            raise RuntimeError(proc.stdout[-3000:] + proc.stderr[-3000:])
        return np.load(result)


def gpu_hits(shapes, ro, rd, h, library=None):
    """bm_preset_hit(shape, ro, rd, h) of each ray on llvmpipe: (N, 4) float32 (normal, t);
    ``library`` as gpu_run's."""
    rays = np.zeros((len(ro), 3, 4), np.float32)
    rays[:, 0, :3], rays[:, 0, 3], rays[:, 1, :3], rays[:, 2, :3] = ro, shapes, rd, h
    return gpu_run("bm_preset_hit(a.w, a.xyz, b.xyz, c.xyz)", rays, library)


def errors(shape, ro, rd, h, got):
    """{'mismatched': rays resolved in float64 whose hit or miss differs, 'unresolved': rays left
    out, 't': largest |t error| / the box's largest half-extent over hits, 'degrees': largest normal
    angle error over hits} of hits ``got`` (gpu_hits) against reference_hits."""
    t, n, resolved = reference_hits(shape, ro, rd, h)
    gpu_t = got[:, 3].astype(np.float64)
    both = resolved & (t >= 0) & (gpu_t >= 0)
    mismatched = resolved & ((t >= 0) != (gpu_t >= 0))
    scale = h.max(-1).astype(np.float64)
    t_error = np.abs(gpu_t - t)[both] / scale[both]
    normal = got[:, :3].astype(np.float64)[both]
    angle = np.arctan2(_length(np.cross(normal, n[both])), (normal * n[both]).sum(-1))
    return {"rays": len(ro), "unresolved": int((~resolved).sum()), "mismatched": int(mismatched.sum()),
            "t": float(t_error.max(initial=0.0)), "t_p99": float(np.percentile(t_error, 99)) if both.any() else 0.0,
            "degrees": float(np.degrees(angle).max(initial=0.0)), "hits": int(both.sum())}

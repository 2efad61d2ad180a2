"""Shader cost per ray of the presets' closed-form hits (shaders/glsl/raymarch.glsl bm_preset_hit)
against the march they replace, on llvmpipe (a compute shader, as tests/helpers/closed_form.py runs
it), with the torus and link taken apart piece by piece.

Rays as a box's fragments cast them: per box (tests/helpers/closed_form.random_rays' sizes, an eye
2..1,000 box sizes away) an 8 x 8 grid of pixels over its silhouette's bounding square, kept where
they enter the box, in grid order (neighbouring lanes, neighbouring pixels, as a rasteriser packs
them); about 400,000 rays per dispatch. Rows, one compiled program each, the preset's id a constant
as the materials compile it:

* floor: the ray read and a vec4 written, nothing solved (the dispatch's own cost per ray);
* march: bm_march over map() = the preset's sdf_preset_* from the box entry to its exit (the
  materials' defaults: 96 steps, epsilon 1e-4 of the box, no secant) and bm_normal's 3 taps at a hit;
* march, hidden: the same march with t_end 0, as a fragment behind the pre-pass's depth marches it
  (one map() then out of its loop; the normal's taps still run, masked: below);
* closed form: bm_preset_hit;
* closed form behind an if no lane takes: bm_preset_hit inside ``if (ro.x > 1e30)``, which no ray
  here passes (the program writes a miss): what a fragment pays for code its lanes skip. llvmpipe
  (Mesa 22.3, lp_bld_nir_soa.c if_cond) runs an if's body for every lane, masked, where no lane
  takes it, and SwiftShader likewise (SpirvEmitter::EmitBranchConditional: "TODO: Optimize for
  case where all lanes take same path"); only a loop stops early, once no lane of the SIMD group
  goes on (at least one pass of its body). So a bounding test that skips a piece by an if saves
  nothing on these renderers, and a hidden fragment's early return skips no solve;
* torus and link only, the closed form with one piece taken out (a profile: wrong pictures, their
  cost): the Newton polish on sd_link, the resolvent cubic's acos / cos / pow (their arguments
  passed through) and, the link only, its two half-tori's quartics (its tubes and normal left).

Per row the best of REPEATS dispatches (wall and the process's CPU time, which counts llvmpipe's
threads); *over floor*: ns per ray less the floor's; *vs march*: that against the march's.

    PYTHONPATH=addon python3 -m bench.bench_closed_form_cost [--glsl DIR] [--presets LINK,TORUS]
    # --glsl: sdf.glsl and raymarch.glsl read from DIR (another revision's, for a before/after)
"""
import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench.common import table
from boxmarch.formats import shader_sources
from tests.helpers import closed_form

HERE = Path(__file__).resolve().parent
BOXES, RAYS, REPEATS = 3000, 400_000, 15
PROGRAM = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Rays { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer Hits { vec4 hits[]; };
uniform int count;
__LIBRARY__
float map(vec3 p) { return sdf_preset___NAME__(p, box_half); }
void main()
{
  int i = int(gl_GlobalInvocationID.x);
  if (i >= count) return;
  vec3 ro = rays[3 * i].xyz;
  vec3 rd = rays[3 * i + 1].xyz;
  box_half = rays[3 * i + 2].xyz;
  __BODY__
}
"""
FLOOR = "hits[i] = vec4(rd, ro.x + box_half.x);"
MARCH = """float t;
  float d;
  int steps;
  vec2 span = bm_box_span(ro, rd, box_half);
  bool hit = bm_march(ro, rd, span.y, 96, 1e-4 * bm_max3(box_half), 1.0, vec2(0.0), t, steps, d);
  vec3 n = hit ? bm_normal(ro + rd * t, d, bm_normal_tap(box_half)) : vec3(0.0);
  hits[i] = vec4(n, hit ? t : -1.0);"""
HIDDEN = MARCH.replace("bm_march(ro, rd, span.y,", "bm_march(ro, rd, 0.0,")
CLOSED = "hits[i] = bm_preset_hit(__ID__, ro, rd, box_half);"
SKIPPED = """vec4 hit = vec4(0.0, 0.0, 0.0, -1.0);
  if (ro.x > 1e30) {
    hit = bm_preset_hit(__ID__, ro, rd, box_half);
  }
  hits[i] = hit;"""
# the closed form's pieces taken out (torus and link): (label, text, its replacement)
POLISH = "  float t = best.w;\n  for (int i = 0; i < "
PIECES = (("no Newton polish", POLISH, POLISH + "0 && i < "),
          ("no half-tori (tubes, normal)", "best = bm_hit_torus_part(ro", "best = best; // (ro"),
          ("no acos / cos / pow in the cubic", "cos(acos(clamp(-q2 / (root * root * root), -1.0, 1.0)) / 3.0)",
           "clamp(-q2 / (root * root * root), -1.0, 1.0)"))
GL_SIDE = """
import sys
import time
import numpy as np
from bench.gl_headless import GL, compute_program, egl_context, storage_buffers
egl_context()
data = dict(np.load(sys.argv[1]))
programs = [compute_program(data[f"source{k}"]) for k in range(int(data["programs"]))]
count = len(data["rays"]) // 3
storage_buffers(data["rays"], count * 16)
best = np.full((len(programs), 2), np.inf)
for _ in range(int(data["repeats"])):
    for k, program in enumerate(programs):  # round robin: the machine's load falls on every row alike
        GL.glUseProgram(program)
        GL.glUniform1i(GL.glGetUniformLocation(program, "count"), count)
        wall, cpu = time.perf_counter(), time.process_time()
        GL.glDispatchCompute((count + 63) // 64, 1, 1)
        GL.glFinish()
        best[k] = np.minimum(best[k], (time.perf_counter() - wall, time.process_time() - cpu))
np.save(sys.argv[2], best / count * 1e9)
"""


def fragment_rays(seed):
    """(ro, rd, h) float32: per box an 8 x 8 grid of rays over its silhouette's bounding square
    from one eye, entering the box (ro at the entry), box by box (module docstring)."""
    rng = np.random.default_rng(seed)
    h = closed_form.random_rays(BOXES, seed=seed)[2].astype(np.float64)
    radius = np.linalg.norm(h, axis=1)
    towards = rng.normal(size=(BOXES, 3))
    towards /= np.linalg.norm(towards, axis=1)[:, None]
    eye = towards * (h.max(1) * 10.0 ** rng.uniform(0.3, 3.0, BOXES))[:, None]
    across = np.cross(towards, rng.normal(size=(BOXES, 3)))
    across /= np.linalg.norm(across, axis=1)[:, None]
    up = np.cross(towards, across)
    u, v = (g.reshape(1, -1, 1) for g in np.meshgrid(np.linspace(-1, 1, 8), np.linspace(-1, 1, 8)))
    target = (u * across[:, None] + v * up[:, None]) * radius[:, None, None]
    rd = target - eye[:, None]
    rd /= np.linalg.norm(rd, axis=2)[..., None]
    eye, h = np.broadcast_to(eye[:, None], rd.shape), np.broadcast_to(h[:, None], rd.shape)
    inv = 1.0 / np.where(np.abs(rd) < 1e-300, 1e-300, rd)
    near, far = (h - eye) * inv, (-h - eye) * inv
    t_in, t_out = np.minimum(near, far).max(-1), np.maximum(near, far).min(-1)
    kept = t_in < t_out
    ro = eye + rd * t_in[..., None]
    return ro[kept].astype(np.float32), rd[kept].astype(np.float32), h[kept].astype(np.float32)


def timed(sources, ro, rd, h):
    """ns per ray (wall, CPU) of each program in ``sources`` over the rays, tiled to about RAYS."""
    rays = np.zeros((len(ro), 3, 4), np.float32)
    rays[:, 0, :3], rays[:, 1, :3], rays[:, 2, :3] = ro, rd, h
    rays = np.tile(rays, (max(1, RAYS // len(ro)), 1, 1))
    with tempfile.TemporaryDirectory() as tmp:
        data, result = Path(tmp) / "programs.npz", Path(tmp) / "times.npy"
        np.savez(data, rays=rays.reshape(-1, 4), programs=len(sources), repeats=REPEATS,
                 **{f"source{k}": source for k, source in enumerate(sources)})
        env = {**os.environ, "EGL_PLATFORM": "surfaceless", "PYTHONPATH": str(HERE.parent)}
        proc = subprocess.run([sys.executable, "-c", GL_SIDE, str(data), str(result)], env=env,
                              capture_output=True, text=True, timeout=600)
        if proc.returncode != 0:
            raise RuntimeError(proc.stdout[-3000:] + proc.stderr[-3000:])
        return np.load(result)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--glsl", help="folder holding the sdf.glsl and raymarch.glsl to time")
    parser.add_argument("--presets", default=",".join(closed_form.PRESETS), help="comma-separated preset names")
    args = parser.parse_args()
    read = (lambda name: (Path(args.glsl) / name).read_text()) if args.glsl else shader_sources.read_glsl
    library = read("sdf.glsl") + "\n" + read("raymarch.glsl")
    rows = []
    for name in args.presets.split(","):
        shape = closed_form.PRESETS.index(name)
        program = PROGRAM.replace("__NAME__", name.lower()).replace("__ID__", f"{float(shape)}")
        labelled = [("floor", library, FLOOR), ("march", library, MARCH),
                    ("march, hidden (t_end 0)", library, HIDDEN), ("closed form", library, CLOSED),
                    ("closed form behind an if no lane takes", library, SKIPPED)]
        if name in ("TORUS", "LINK"):
            for label, text, replacement in PIECES[::2] if name == "TORUS" else PIECES:
                if text not in library:
                    raise SystemExit(f"boxmarch: bench_closed_form_cost: {label!r}: its text is not in raymarch.glsl")
                labelled.append((f"closed form, {label}", library.replace(text, replacement), CLOSED))
        times = timed([program.replace("__LIBRARY__", lib).replace("__BODY__", body).replace("__ID__", f"{float(shape)}")
                       for _, lib, body in labelled], *fragment_rays(seed=shape))
        march = times[1, 1] - times[0, 1]
        for (label, _, _), (wall, cpu) in zip(labelled, times):
            over = cpu - times[0, 1]
            rows.append([name, label, f"{wall:.1f}", f"{cpu:.1f}", f"{over:.1f}" if label != "floor" else "",
                         f"{over / march:.2f}x" if label != "floor" else ""])
    print(table(["preset", "program", "wall ns/ray", "CPU ns/ray", "over floor", "vs march"], rows))


if __name__ == "__main__":
    main()

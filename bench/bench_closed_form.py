"""Error of the presets' closed-form hits (shaders/glsl/raymarch.glsl bm_preset_hit) run in float32
on llvmpipe (a compute shader, tests/helpers/closed_form.py) against a float64 sphere tracing of the
exact SDFs to 1e-12 of the box: RAYS rays per preset as fragments cast them (boxes of largest
half-extent 0.01..1000, eyes 1..10,000 box sizes away, 20 % from an eye inside the box), and the
torus and link again without the Newton step on the SDF that polishes the quartic's root
(the method's own error). Errors relative to the box's largest half-extent; normal errors in
degrees; *unresolved*: rays float64 cannot call at float32 (grazing within 0.6 degrees, or missing
by under 1e-5 of the box), left out.

    PYTHONPATH=addon python3 -m bench.bench_closed_form [RAYS]
"""
import sys

import numpy as np

from bench.common import table
from boxmarch.formats import shader_sources
from tests.helpers import closed_form

RAYS = 20_000


def rays(shape, count):
    ro, rd, h, from_eye = closed_form.random_rays(count, seed=1000 + shape)
    outside = ~from_eye | (closed_form.preset_distance(shape, ro.astype(np.float64), h.astype(np.float64)) > 0)
    return ro[outside], rd[outside], h[outside]


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else RAYS
    library = shader_sources.read_glsl("sdf.glsl") + "\n" + shader_sources.read_glsl("raymarch.glsl")
    # bm_hit_link's polish loop taken out: the quartic's roots as solved
    polish = "  float t = best.w;\n  for (int i = 0; i < 1; ++i) {"
    unpolished = library.replace(polish, polish.replace("i < 1", "i < 0"))
    assert unpolished != library
    rows = []
    for shape, name in enumerate(closed_form.PRESETS):
        ro, rd, h = rays(shape, count)
        ids = np.full(len(ro), shape, np.float32)
        for label, source in (("closed form", library), ("no Newton polish", unpolished)):
            if label != "closed form" and name not in ("TORUS", "LINK"):
                continue
            e = closed_form.errors(shape, ro, rd, h, closed_form.gpu_hits(ids, ro, rd, h, source))
            rows.append([name, label, e["rays"], e["hits"], e["unresolved"], e["mismatched"], f"{e['t']:.2e}",
                         f"{e['t_p99']:.2e}", f"{e['degrees']:.4f}"])
    print(table(["preset", "solve", "rays", "hits", "unresolved", "hit/miss wrong", "max |dt| / h", "p99 |dt| / h",
                 "max normal deg"], rows))


if __name__ == "__main__":
    main()

"""The presets' closed-form hits (shaders/glsl/raymarch.glsl bm_preset_hit), compiled and run by
Mesa's llvmpipe in a compute shader, against a float64 sphere tracing of the exact SDFs written
from sdf.glsl's definitions (tests/helpers/closed_form.py): 2,000 rays per preset as fragments
cast them, boxes of 0.01..1000 seen from 1 to 10,000 box sizes, 20 % from an eye inside the box.
Bars (measured: docs/ACCURACY.md, "Closed-form hits"): every ray that float64 resolves hits or
misses alike; the hit distance within 4e-6 of the box's largest half-extent (float32 keeps about
6e-8 of it), the normal within 0.01 degrees. Slow tier: about 15 s."""
import numpy as np
import pytest

from tests.helpers import closed_form

pytestmark = pytest.mark.slow
RAYS = 2000


def rays_of_every_preset():
    """(shapes, ro, rd, h) of RAYS rays per preset, those from an eye inside the shape left out
    (the fragment hits at 0 there without solving)."""
    parts = []
    for shape in range(len(closed_form.PRESETS)):
        ro, rd, h, from_eye = closed_form.random_rays(RAYS, seed=38 + shape)
        outside = ~from_eye | (closed_form.preset_distance(shape, ro.astype(np.float64), h.astype(np.float64)) > 0)
        parts.append((np.full(outside.sum(), shape, np.float32), ro[outside], rd[outside], h[outside]))
    return tuple(np.concatenate(column) for column in zip(*parts))


@pytest.fixture(scope="module")
def solved():
    shapes, ro, rd, h = rays_of_every_preset()
    return shapes, ro, rd, h, closed_form.gpu_hits(shapes, ro, rd, h)


def preset_errors(solved, shape, hits=None):
    shapes, ro, rd, h, got = solved
    rows = shapes == shape
    return closed_form.errors(shape, ro[rows], rd[rows], h[rows], (got if hits is None else hits)[rows])


@pytest.mark.parametrize("shape", closed_form.PRESETS)
def test_closed_form_hit_matches_float64(solved, shape):
    e = preset_errors(solved, closed_form.PRESETS.index(shape))
    assert e["hits"] > 0.3 * RAYS and e["unresolved"] < 0.01 * RAYS, e
    assert e["mismatched"] == 0 and e["t"] <= 4e-6 and e["degrees"] <= 0.01, e


def test_the_comparison_sees_a_wrong_preset_and_a_flipped_normal(solved):
    """Negative controls: each preset's rays solved as the next preset's shape, and the normals
    of the right one turned around, must fail the bars."""
    shapes, ro, rd, h, got = solved
    wrong = closed_form.gpu_hits((shapes + 1) % len(closed_form.PRESETS), ro, rd, h)
    flipped = got * np.array([-1, -1, -1, 1], np.float32)
    for shape in range(len(closed_form.PRESETS)):
        e = preset_errors(solved, shape, wrong)
        assert e["mismatched"] > 0 or e["t"] > 1e-3, (shape, e)
        assert preset_errors(solved, shape, flipped)["degrees"] > 170.0


# A fragment's start is its box face's point (-f) rounded: where the vertices lie far from the
# object's origin, by much more than float32 keeps of the box (issue 36, preview seeds 2 and 80:
# ROUNDED_BOX boxes 1,200 and 4,600 units out, the start ~1e-4 inside a 0.0225 face, in the
# rounded edge's region). Where the shape touches the face there, the start lies a hair inside the
# shape, and the right hit is at once. The solves alone (bm_preset_solve) rejected the piece the
# start lies in (its near root a hair behind) and took a farther piece's root: the rounded box's
# normal there is max(|p| - size, 0) = 0 (the preview shaded it NaN), the torus and link hit late
# or missed; bm_preset_hit tests the start first.
@pytest.mark.parametrize("shape", closed_form.PRESETS)
def test_a_start_a_rounding_inside_the_shape_hits_at_once_with_a_unit_normal(shape):
    """Face starts of random_rays moved 1e-3 of the box along the ray (inside the box); those the
    float64 SDF puts inside the shape must hit within 2e-3 of the box with a unit normal."""
    index = closed_form.PRESETS.index(shape)
    ro, rd, h, _ = closed_form.random_rays(RAYS, seed=80 + index, from_eye_share=0.0)
    ro = (ro.astype(np.float64) + rd * (1e-3 * h.max(-1))[:, None]).astype(np.float32)
    inside = closed_form.preset_distance(index, ro.astype(np.float64), h.astype(np.float64)) < 0
    got = closed_form.gpu_hits(np.full(inside.sum(), index, np.float32), ro[inside], rd[inside], h[inside])
    hits = got[:, 3] >= 0
    no_normal = int((hits & (np.abs(np.linalg.norm(got[:, :3].astype(np.float64), axis=-1) - 1.0) >= 1e-3)).sum())
    late_or_missed = int((~hits | (got[:, 3] > 2e-3 * h[inside].max(-1))).sum())
    assert inside.sum() > 0
    assert late_or_missed == 0 and no_normal == 0, (
        f"{shape}: {inside.sum()} starts inside, {late_or_missed} late or missed, {no_normal} hits without a unit normal")


def test_a_start_at_an_edge_takes_the_face_the_ray_enters_by():
    """A box face's start at its edge with a face the ray leaves by, rounded onto that face (1e-6 of
    the half-extent nearer it than the face the ray enters by), hits at once with the entered
    face's normal (cut battery seed 2387: at a box's silhouette the front face's fragment was
    shaded with the far face's normal, turned away from the eye); a start in the middle of a face
    the ray leaves by keeps that face's normal (a back face's own fragment, drawn behind)."""
    rng = np.random.default_rng(2387)
    n = 400
    h = rng.uniform(0.01, 100.0, (n, 3)).astype(np.float32)
    rd = rng.normal(size=(n, 3))
    rd[:, 0], rd[:, 1] = np.abs(rd[:, 0]) + 0.05, -np.abs(rd[:, 1]) - 0.05  # leaves by +x, enters by +y
    rd = (rd / np.linalg.norm(rd, axis=-1, keepdims=True)).astype(np.float32)
    z = rng.uniform(-0.5, 0.5, n)
    edge = np.stack([1.0 - 1e-6 * np.ones(n), 1.0 - 2e-6 * np.ones(n), z], -1)
    middle = np.stack([np.ones(n), rng.uniform(-0.5, 0.5, n), z], -1)
    # both sets in one run of the compute shader
    ro = (np.concatenate([edge, middle]) * np.concatenate([h, h])).astype(np.float32)
    got = closed_form.gpu_hits(np.zeros(2 * n, np.float32), ro, np.concatenate([rd, rd]), np.concatenate([h, h]))
    for part, starts, wanted in ((got[:n], edge, np.array([0.0, 1.0, 0.0])),
                                 (got[n:], middle, np.array([1.0, 0.0, 0.0]))):
        wrong = int((np.abs(part[:, :3] - wanted).max(-1) > 1e-6).sum() + (part[:, 3] != 0.0).sum())
        assert wrong == 0, f"{wrong} of {n} starts at {starts[0]} x h: normals {part[:3, :3]}"

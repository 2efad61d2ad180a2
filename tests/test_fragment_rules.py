"""The rules of shaders/glsl/raymarch.glsl that decide, in every engine, when a rasterised fragment
draws nothing whatever its winding (so that culling back faces changes nothing there; docs/PREVIEW.md),
compiled and run by Mesa's llvmpipe against what float64 geometry says:

* bm_grazes_box: a ray that meets its box only on the box's surface (along a silhouette edge, at a
  corner) has no chord; one that crosses the box, or a flat box (a half-extent of 0), has one.
* bm_hit_depth: a march from its face whose hit lies in front of the near plane is clipped (-1);
  one behind it keeps its depth (never nearer than its face, at most 1); a march from the eye
  keeps its own depth, 0 where clip w is not positive.

Slow tier: one llvmpipe compute run each."""
import numpy as np
import pytest

from tests.helpers import closed_form

pytestmark = pytest.mark.slow
RAYS = 2000


def _unit(v):
    return v / np.linalg.norm(v)


def grazing_and_crossing_rays(rng):
    """(slots, kinds): per ray ro (slot 0), rd (slot 1), the box's half-extents (slot 2), float32
    as the shader reads them, each exact in float32 where it lies on the box's surface."""
    slots, kinds = np.zeros((RAYS, 3, 4), np.float32), []
    for i in range(RAYS):
        h = (10.0 ** rng.uniform(-3, 3)) * rng.uniform(0.01, 1.0, 3)
        kind = ("edge", "corner", "crossing", "flat")[i % 4]
        if kind == "flat":
            h[rng.integers(3)] = 0.0
        h = h.astype(np.float32).astype(np.float64)
        sign = rng.choice([-1.0, 1.0], 3)
        ro = rng.uniform(-0.9, 0.9, 3) * h
        if kind in ("edge", "corner"):
            on = rng.permutation(3)[:2] if kind == "edge" else np.arange(3)
            ro[on] = sign[on] * h[on]
            # away from the box along one of those axes, into it along another: the ray passes
            # the edge (the corner) from outside to outside
            d = rng.normal(size=3)
            d[on] = np.abs(d[on]) * sign[on]
            d[on[0]] = np.abs(d[on[0]]) * -sign[on[0]]
            d[on] += np.sign(d[on]) * 0.05
        elif kind == "crossing":
            # from a face's inner part into the box
            axis = rng.integers(3)
            ro[axis] = sign[axis] * h[axis]
            d = rng.normal(size=3)
            d[axis] = -sign[axis] * (np.abs(d[axis]) + 0.2)
        else:
            # across a flat box, through its face's inner part
            axis = int(np.argmin(h))
            ro[axis] = 0.0
            d = rng.normal(size=3)
            d[axis] = np.abs(d[axis]) + 0.2
        slots[i, 0, :3], slots[i, 1, :3], slots[i, 2, :3] = ro, _unit(d), h
        kinds.append(kind)
    return slots, kinds


def test_a_ray_grazes_its_box_only_where_it_has_no_chord():
    slots, kinds = grazing_and_crossing_rays(np.random.default_rng(3369))
    got = closed_form.gpu_run("vec4(bm_grazes_box(bm_box_span(a.xyz, b.xyz, c.xyz), c.xyz) ? 1.0 : 0.0)", slots)
    grazes = got[:, 0] > 0.5
    kinds = np.array(kinds)
    for kind, expected in (("edge", True), ("corner", True), ("crossing", False), ("flat", False)):
        wrong = np.flatnonzero((kinds == kind) & (grazes != expected))
        assert wrong.size == 0, f"{kind}: {wrong.size} of {np.sum(kinds == kind)} rays, e.g. {slots[wrong[:3]].tolist()}"


def test_a_hit_in_front_of_the_near_plane_is_clipped_from_a_face_only():
    rng = np.random.default_rng(3188)
    slots = np.zeros((RAYS, 3, 4), np.float32)
    window = np.where(rng.random(RAYS) < 0.5, -(10.0 ** rng.uniform(-8, -1, RAYS)), rng.uniform(0.0, 1.2, RAYS))
    face = np.minimum(window, window - rng.uniform(0.0, 0.1, RAYS))  # a face lies no deeper than its hit
    clip_w = np.where(rng.random(RAYS) < 0.2, -rng.uniform(0.0, 1e-3, RAYS), 10.0 ** rng.uniform(-6, 3, RAYS))
    own = rng.random(RAYS) < 0.3
    slots[:, 0, 0], slots[:, 0, 1], slots[:, 0, 2], slots[:, 0, 3] = window, clip_w, face, own
    got = closed_form.gpu_run("vec4(bm_hit_depth(a.x, a.y, a.z, a.w > 0.5))", slots)[:, 0].astype(np.float64)
    window, clip_w, face = (slots[:, 0, k].astype(np.float64) for k in range(3))
    from_face = np.maximum(window, face)
    expected = np.where(own, np.where(clip_w > 0, np.clip(window, 0.0, 1.0), 0.0),
                        np.where(from_face < 0, -1.0, np.minimum(from_face, 1.0)))
    assert np.sum(~own & (from_face < 0)) > 100, "too few hits in front of the near plane drawn"
    wrong = np.flatnonzero(got != expected)
    assert wrong.size == 0, f"{wrong.size} of {RAYS}: got {got[wrong[:5]]}, expected {expected[wrong[:5]]}"

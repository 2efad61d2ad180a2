"""The rules of shaders/glsl/raymarch.glsl that decide, in every engine, which rasterised fragments
draw nothing (so that culling back faces changes nothing; docs/PREVIEW.md), compiled and run by
Mesa's llvmpipe against what float64 geometry says:

* bm_from_eye: a back face is its box's far side where its ray leaves the box there or meets the
  box only on its surface (along a silhouette edge, through a corner), and draws nothing unless
  the box holds the eye; a back face where the ray enters (an inside-out box's near side) and
  every front face not in a box holding the eye march from their face.
* bm_hit_depth: a march from its face whose hit lies in front of the near plane is clipped (-1);
  one behind it keeps its depth (never nearer than its face, at most 1); a march from the eye
  keeps its own depth, 0 where clip w is not positive.

Slow tier: one llvmpipe compute run each."""
import numpy as np
import pytest

from tests.helpers import closed_form

pytestmark = pytest.mark.slow
RAYS = 2000


def fragments(rng):
    """(slots, kinds): per fragment ro (slot 0; w: 1 for a front face), rd (slot 1; w: the eye's
    distance, 0 for an orthographic view), the box's half-extents (slot 2), float32 as the shader
    reads them, each start exact in float32 where it lies on the box's surface; kind: "edge" (the
    ray meets the box only along an edge), "corner" (only at a corner), "entry", "exit", and for
    front faces of exits in a perspective view "eye inside" (the eye within the box's reach behind
    the fragment) or "eye outside"."""
    slots, kinds = np.zeros((RAYS, 3, 4), np.float32), []
    for i in range(RAYS):
        h = ((10.0 ** rng.uniform(-3, 3)) * rng.uniform(0.01, 1.0, 3)).astype(np.float32).astype(np.float64)
        kind = ("edge", "corner", "entry", "exit")[i % 4]
        sign = rng.choice([-1.0, 1.0], 3)
        ro = rng.uniform(-0.9, 0.9, 3) * h
        d = rng.normal(size=3)
        if kind in ("edge", "corner"):
            on = rng.permutation(3)[:2] if kind == "edge" else np.arange(3)
            ro[on] = sign[on] * h[on]
            # away from the box along all but one of those axes, into it along that one: the ray
            # passes the edge (the corner) from outside to outside
            d[on] = (np.abs(d[on]) + 0.05) * sign[on]
            d[on[0]] = -d[on[0]]
        else:
            # from a face's inner part, into the box or out of it
            axis = rng.integers(3)
            ro[axis] = sign[axis] * h[axis]
            d[axis] = (np.abs(d[axis]) + 0.2) * (-sign[axis] if kind == "entry" else sign[axis])
        d = d / np.linalg.norm(d)
        front = rng.random() < 0.5
        eye = 0.0
        if front and kind == "exit" and rng.random() < 0.5:
            # the chord behind the fragment, in float64
            inv = 1.0 / np.where(np.abs(d) > 1e-12, np.abs(d), 1e-12)
            s_d = np.where(d < 0, -1.0, 1.0)
            chord = -np.max((-h - s_d * ro) * inv)
            inside = rng.random() < 0.5
            eye = chord * (rng.uniform(0.05, 0.95) if inside else rng.uniform(1.05, 3.0))
            kind = "eye inside" if inside else "eye outside"
        slots[i, 0, :3], slots[i, 0, 3], slots[i, 1, :3], slots[i, 1, 3], slots[i, 2, :3] = ro, front, d, eye, h
        kinds.append(("front " if front else "back ") + kind)
    return slots, kinds


def test_a_back_face_where_the_ray_leaves_or_only_touches_its_box_is_the_far_side():
    slots, kinds = fragments(np.random.default_rng(3369))
    got = closed_form.gpu_run("vec4(bm_from_eye(bm_box_span(a.xyz, b.xyz, c.xyz), a.w > 0.5, b.w > 0.0, b.w) ? 1.0 : 0.0)",
                              slots)
    far_side = got[:, 0] > 0.5
    kinds = np.array(kinds)
    expected = {"back edge": True, "back corner": True, "back exit": True, "back entry": False,
                "front edge": False, "front corner": False, "front exit": False, "front entry": False,
                "front eye inside": True, "front eye outside": False}
    assert set(kinds) == set(expected)
    for kind, far in expected.items():
        wrong = np.flatnonzero((kinds == kind) & (far_side != far))
        assert wrong.size == 0, f"{kind}: {wrong.size} of {np.sum(kinds == kind)}, e.g. {slots[wrong[:2]].tolist()}"


def test_a_hit_in_front_of_the_near_plane_is_clipped_from_a_face_only():
    rng = np.random.default_rng(3188)
    slots = np.zeros((RAYS, 3, 4), np.float32)
    window = np.where(rng.random(RAYS) < 0.5, -(10.0 ** rng.uniform(-8, -1, RAYS)), rng.uniform(0.0, 1.2, RAYS))
    face = window - rng.uniform(0.0, 0.1, RAYS)  # a face lies no deeper than its hit
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

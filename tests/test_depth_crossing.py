"""bm_depth_crossing (shaders/glsl/raymarch.glsl), the distance at which a march stops because
nothing beyond it is visible (the preview's occluder pre-pass and resolved passes, three.js's
pre-pass), compiled and run by Mesa's llvmpipe, against the depth of the ray's points past it
computed in float64 from the same clip-space ray: no point beyond the bound may lie at or in front
of the limit, with a point's depth as bm_hit_depth gives a march from the eye its hit's (0 where
clip w is not positive). Rays from the eye (clip w 0 give or take rounding, some directions rounded
away from the view), from faces, and orthographic. Slow tier: one llvmpipe compute run."""
from collections import Counter

import numpy as np
import pytest

from tests.helpers import closed_form

pytestmark = pytest.mark.slow
RAYS = 3000


def perspective(near, far, fov):
    f = 1.0 / np.tan(0.5 * fov)
    return np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
                     [0, 0, -1, 0]])


def orthographic(near, far, size):
    return np.array([[1 / size, 0, 0, 0], [0, 1 / size, 0, 0], [0, 0, -2 / (far - near), -(far + near) / (far - near)],
                     [0, 0, 0, 1]])


def random_rays(rng):
    """(slots, kinds): per ray, c0 and c1 (the ray c0 + t c1 in GL clip space, t in view units) and
    the limit's NDC z in slot 2's x, float32 as the shader reads them; and the ray's kind."""
    slots, kinds = np.zeros((RAYS, 3, 4), np.float32), []
    for i in range(RAYS):
        near = 10.0 ** rng.uniform(-6, 0)
        far = near * 10.0 ** rng.uniform(1, 5)
        kind = ("eye", "eye rounded away", "face", "orthographic")[i % 4]
        projection = (orthographic(near, far, far * rng.uniform(0.01, 1)) if kind == "orthographic"
                      else perspective(near, far, rng.uniform(0.3, 2.0)))
        d = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), -1.0])
        if kind == "eye rounded away":
            d[2] = rng.uniform(0.0, 0.3)  # clip w falls or stays along the ray: a direction rounding turned
        d /= np.linalg.norm(d)
        if kind.startswith("eye"):
            start = np.zeros(3)
        else:
            start = d / -d[2] * rng.uniform(near, 0.5 * far)  # a point of the view volume on the ray
        c0 = projection @ np.append(start, 1.0)
        if kind.startswith("eye"):
            # the eye's clip z and w as float32 products of coordinates far from the object's origin leave them
            c0[2:] += rng.normal(size=2) * 10.0 ** rng.uniform(-9, -3)
        c1 = projection @ np.append(d, 0.0)
        # the limit: half of them the depth of a point ahead on the ray (most random depths lie
        # behind a face's, a window depth crowding towards 1)
        ahead = projection @ np.append(start + d * rng.uniform(0.0, 0.3) * far, 1.0)
        limit = 0.5 + 0.5 * ahead[2] / ahead[3] if i % 8 < 4 and ahead[3] > 0 else rng.uniform(0.0, 1.0)
        slots[i, 0], slots[i, 1], slots[i, 2, 0] = c0, c1, 2.0 * np.clip(limit, 0.0, 1.0) - 1.0
        kinds.append(kind)
    return slots, kinds


def hit_depth(c0, c1, t):
    """The window depth of the ray's point at t as a march from the eye writes it (bm_hit_depth), in
    float64: 0 where clip w is not positive, else z / w mapped to [0, 1] and clamped."""
    clip = c0[None, :] + t[:, None] * c1[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.clip(0.5 + 0.5 * clip[:, 2] / clip[:, 3], 0.0, 1.0)
    return np.where(clip[:, 3] > 0.0, depth, 0.0)


def test_no_point_beyond_the_crossing_lies_in_front_of_the_limit():
    slots, kinds = random_rays(np.random.default_rng(2333))
    got = closed_form.gpu_run("vec4(bm_depth_crossing(a, b, c.x))", slots)[:, 0].astype(np.float64)
    wrong, lost, bounded = Counter(), Counter(), Counter()
    steps = 1.0 + np.geomspace(1e-4, 1e6, 60)  # past the bound (a hit at it is kept)
    # in float64, the float32 ray the shader read
    for slot, kind, bound in zip(slots.astype(np.float64), kinds, got):
        c0, c1, ndc_z = slot[0], slot[1], slot[2, 0]
        if bound >= 1e30:
            # no bound: right, but where the float64 ray passes the limit ahead with w rising (no
            # depth 0 beyond), the march is left unbounded: a lost saving
            reach = ndc_z * c0[3] - c0[2]
            rate = c1[2] - ndc_z * c1[3]
            lost[kind] += int(rate > 0 and c1[3] > 0 and c0[3] > 0 and reach / rate > 0)
            continue
        bounded[kind] += 1
        beyond = hit_depth(c0, c1, bound * steps)
        # float32 rounds the crossing: a point may sit within 1e-6 of window depth of the limit
        wrong[kind] += int((beyond <= 0.5 * ndc_z + 0.5 - 1e-6).any())
    assert sum(wrong.values()) == 0, f"bounds with a point beyond at or in front of the limit: {wrong} of {bounded}"
    assert sum(lost.values()) == 0, f"rays passing the limit left unbounded: {lost}"
    # most rays of every kind but the degenerate one are bounded (the test is not vacuous)
    assert all(bounded[kind] > 0.3 * RAYS / 4 for kind in ("eye", "face", "orthographic")), bounded

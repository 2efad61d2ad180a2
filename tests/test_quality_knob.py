"""The quality knob of the CPU reference (core.render_boxes' quality, the shaders' bm_quality)
against geometry known independently: spheres whose silhouettes and depths are worked out here,
and a heap of links compared with its own full-quality render within the figures docs/BENCHMARKS.md
states ("The quality knob")."""
import numpy as np
import pytest

from boxmarch import core

QUALITIES = (1.0, 0.75, 0.5, 0.25)
SIZE = 96  # pixels; x, y in [-1, 1] map onto them
PIXEL = 2.0 / SIZE
EPSILON = 1e-4
NEAR, FAR = 0.1, 10.0


def orthographic():
    """Looks down -z from z = 0; window depth = (-z - NEAR) / (FAR - NEAR)."""
    m = np.eye(4)
    m[2, 2], m[2, 3] = -2 / (FAR - NEAR), -(FAR + NEAR) / (FAR - NEAR)
    return m


def spheres(count=40, seed=7):
    """SPHERE boxes (radius = the smallest half-extent) 3 to 8 pixels in radius, so no box falls
    under the one-tap size (4 x (1 - quality) pixels) at any setting, at sub-pixel offsets."""
    rng = np.random.default_rng(seed)
    radius = rng.uniform(3.0, 8.0, count) * PIXEL
    centres = np.column_stack([rng.uniform(-0.85, 0.85, (count, 2)), rng.uniform(-8.0, -2.0, count)])
    half = np.column_stack([radius, radius * rng.uniform(1.0, 1.5, count), radius * rng.uniform(1.0, 1.5, count)])
    return centres, half, radius


def render_spheres(centres, half, quality):
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(centres), 1))
    return core.render_boxes(centres, q, half, orthographic(), np.eye(4), SIZE, SIZE, sdf="SPHERE",
                             epsilon=EPSILON, max_steps=64, quality=quality)


def sphere_truth(centres, radius):
    """Per pixel: distance from the pixel's ray to the nearest sphere's silhouette (negative
    inside), distance to the nearest silhouette of any sphere (the rims, where depth is steep and a
    hit within epsilon of a sphere counts) and the window depth of the nearest sphere's front
    surface (1 where none)."""
    centre_x = -1.0 + PIXEL * (np.arange(SIZE) + 0.5)
    x, y = np.meshgrid(centre_x, -centre_x)  # rows from the top
    rho = np.hypot(x[..., None] - centres[:, 0], y[..., None] - centres[:, 1])
    front = np.where(rho < radius, centres[:, 2] + np.sqrt(np.maximum(radius**2 - rho**2, 0.0)), -np.inf).max(-1)
    depth = np.where(np.isfinite(front), (-front - NEAR) / (FAR - NEAR), 1.0)
    return (rho - radius).min(-1), np.abs(rho - radius).min(-1), depth


@pytest.mark.parametrize("quality", QUALITIES)
def test_silhouettes_and_depths_stay_on_the_spheres_at_every_setting(quality):
    """A covered pixel's ray passes within epsilon of a sphere and every ray through a sphere's
    core hits; where a ray crosses a sphere, the depth is that sphere's within a twentieth of a
    pixel. A hit distance that grows with the pixel (0.28 px at quality 0.25) fails the first."""
    centres, half, radius = spheres()
    result = render_spheres(centres, half, quality)
    outside, rim, depth = sphere_truth(centres, radius)
    covered = result.depth < 1.0
    assert covered.sum() > 2000
    fat = covered & (outside > EPSILON + 1e-5)
    assert not fat.any(), f"{fat.sum()} pixels covered outside the spheres, up to {outside[fat].max() / PIXEL:.3f} px"
    holes = ~covered & (outside < -1e-3 * PIXEL)
    assert not holes.any(), f"{holes.sum()} pixels inside a sphere not covered"
    inner = covered & (outside < 0) & (rim > 0.05 * PIXEL)  # rays crossing, away from every rim
    error = np.abs(result.depth - depth)[inner] * (FAR - NEAR)
    assert error.max() < 0.05 * PIXEL, error.max() / PIXEL


def test_the_sphere_check_catches_a_silhouette_half_a_pixel_out():
    """Negative control: spheres half a pixel larger than the truth the check is given."""
    centres, half, radius = spheres()
    covered = render_spheres(centres, half + 0.5 * PIXEL, 1.0).depth < 1.0
    outside, _, _ = sphere_truth(centres, radius)
    assert (covered & (outside > EPSILON + 1e-5)).sum() > 100


def link_heap(count=300, seed=11):
    """LINK boxes (0.46 x 0.23 x 0.06 scaled to 0.3 long) heaped at random orientations in front
    of an orthographic camera that frames them on 160 x 160 px (about 24 px a link)."""
    rng = np.random.default_rng(seed)
    origins = np.column_stack([rng.uniform(-0.9, 0.9, (count, 2)), rng.uniform(-6.0, -3.0, count)])
    axes = rng.normal(size=(count, 4))
    quaternions = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    quaternions *= np.where(quaternions[:, 3:] < 0, -1.0, 1.0)
    return origins, quaternions, np.tile([0.15, 0.075, 0.02], (count, 1))


def pixel_changes(result, reference):
    """(coverage, colour, depth) changed as shares of the pixels covered in either image: coverage
    in one only; colour moving > 1/255 in a channel, depth > a tenth of a pixel, where both hit
    (bench/bench_quality.py's measures, orthographic here: a pixel is 2 / size wide)."""
    a, b = result.depth < 1, reference.depth < 1
    either = max(int((a | b).sum()), 1)
    both = a & b
    colour = both & (np.abs(result.rgba[..., :3] - reference.rgba[..., :3]).max(-1) > 1 / 255)
    depth = both & (np.abs(result.depth - reference.depth) * (FAR - NEAR) > 0.1 * 2.0 / len(a))
    return tuple(int(x.sum()) / either for x in (a != b, colour, depth))


# The largest share of pixels any setting changes against quality 1 on this heap, as
# docs/BENCHMARKS.md ("The quality knob") states it: coverage 0.05 %, colour 2 %, depth 0.5 %.
CLAIMED = {"coverage": 0.0005, "colour": 0.02, "depth": 0.005}


def test_link_heap_changes_at_most_what_the_docs_claim():
    origins, quaternions, half = link_heap()
    size = 160

    def render(quality):
        return core.render_boxes(origins, quaternions, half, orthographic(), np.eye(4), size, size, sdf="LINK",
                                 epsilon=EPSILON, max_steps=64, quality=quality)

    full = render(1.0)
    assert (full.depth < 1).mean() > 0.3
    evaluations = [full.cost["sdf_evaluations"]]
    for quality in QUALITIES[1:]:
        result = render(quality)
        assert result.cost["lod_fragments"] == 0  # every link is wider than the one-tap size
        changed = dict(zip(CLAIMED, pixel_changes(result, full)))
        assert all(changed[k] <= CLAIMED[k] for k in CLAIMED), (quality, changed)
        evaluations.append(result.cost["sdf_evaluations"])
    assert evaluations == sorted(evaluations, reverse=True) and evaluations[-1] < 0.9 * evaluations[0], evaluations

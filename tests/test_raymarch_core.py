"""The CPU reference raymarcher (boxmarch.core.raymarch / render_boxes) against closed forms."""
import itertools

import numpy as np
import pytest

from boxmarch import core, scenes


def test_sdf_presets_at_known_points():
    h = np.array([1.0, 0.6, 0.2])
    cases = {
        "BOX": [([2.0, 0, 0], 1.0), ([0, 0, 0], -0.2), ([1.3, 1.0, 0], 0.5)],
        "SPHERE": [([0, 0, 1.0], 0.8), ([0, 0, 0], -0.2)],
        "ROUNDED_BOX": [([2.0, 0, 0], 1.0), ([1.0, 0.6, 0], np.hypot(0.05, 0.05) - 0.05)],
        "CAPSULE": [([0, 0, 0.5], 0.3), ([1.5, 0, 0], 0.5)],       # r = 0.2, segment x in [-0.8, 0.8]
        "CYLINDER": [([0, 0, 0.5], 0.3), ([1.0, 0, 0], 0.4)],      # r = 0.6, half-height 0.2
        "TORUS": [([0.5, 0, 0], -0.1), ([0, 0, 0], 0.2)],          # minor 0.2, major 0.4
    }
    for sdf, points in cases.items():
        p = np.array([q for q, _ in points], np.float32)
        expected = np.array([d for _, d in points])
        assert np.allclose(core.sdf_distance(sdf, p, h), expected, atol=1e-6), sdf


def test_link_fills_its_box():
    h = np.array([1.0, 0.5, 0.2])
    # outermost points of the link along each axis lie on its surface
    p = np.array([[1.0, 0, 0], [0, 0.5, 0], [0.5, 0.375, 0.125]], np.float32)
    d = core.sdf_distance("LINK", p, h)
    assert np.allclose(d[:2], 0.0, atol=1e-6)
    assert d[2] == pytest.approx(0.0, abs=1e-6)  # on the tube: ring 0.375, thickness 0.125


@pytest.mark.parametrize("sdf", ["CAPSULE", "CYLINDER", "TORUS", "LINK", "BOX", "SPHERE", "ROUNDED_BOX"])
def test_presets_read_the_box_axes_by_extent(sdf):
    """A preset draws the same shape whichever local axis holds which extent: the distance at p in
    a box of half-extents h equals the distance at p's components permuted with h's, for all six
    orders (so a default bake, whose axis order is the frame's, draws what a sorted bake draws)."""
    rng = np.random.default_rng(29)
    h = np.array([1.0, 0.6, 0.2])
    p = rng.uniform(-1.2, 1.2, (500, 3)).astype(np.float32)
    sorted_distance = core.sdf_distance(sdf, p, h)
    for order in itertools.permutations(range(3)):
        order = list(order)
        permuted = core.sdf_distance(sdf, np.ascontiguousarray(p[:, order]), h[order])
        np.testing.assert_allclose(permuted, sorted_distance, atol=1e-6, err_msg=f"{sdf} axes {order}")


def test_near_equal_extents_keep_their_axis_order():
    """Two sides within 0.1% of each other count as equal and keep the order x, y, z, so boxes of
    one shape baked with float noise read their axes alike: a 1 x 0.6 x 0.6 link box (long side
    along local z) puts its ring across the first of the tied axes, local x, either way round the
    noise falls (the ring's outer edge at x = 0.3 or 0.3002 is on the surface; its wire's side,
    along y, is not)."""
    for h in ([0.3, 0.3002, 0.5], [0.3002, 0.3, 0.5]):
        points = np.array([[h[0], 0.0, 0.0], [0.0, h[1], 0.0]], np.float32)
        d = core.sdf_distance("LINK", points, np.array(h))
        assert d[0] == pytest.approx(0.0, abs=1e-6) and d[1] > 0.1, (h, d)


def test_cylinder_stands_along_a_rod_and_across_a_disc():
    """Closed forms: a rod's cylinder runs along its long axis, a disc's along its short one."""
    cases = [([1.0, 0.2, 0.2], [1.3, 0.0, 0.0], 0.3), ([0.2, 1.0, 0.2], [0.0, 0.0, 0.5], 0.3),
             ([1.0, 1.0, 0.1], [0.0, 0.0, 0.5], 0.4), ([0.1, 1.0, 1.0], [0.0, 1.2, 0.0], 0.2)]
    for h, point, distance in cases:
        d = core.sdf_distance("CYLINDER", np.array([point], np.float32), np.array(h))
        assert d[0] == pytest.approx(distance, abs=1e-6), (h, point)


def test_sphere_hits_match_ray_sphere_intersection():
    rng = np.random.default_rng(3)
    n = 4000
    origins = rng.normal(size=(n, 3))
    origins *= 3 / np.linalg.norm(origins, axis=1, keepdims=True)  # all outside the box
    targets = rng.uniform(-0.8, 0.8, (n, 3))
    directions = targets - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    h = np.array([1.0, 0.8, 0.9])
    r = core.raymarch(origins, directions, h, sdf="SPHERE", max_steps=128, epsilon=1e-5)
    radius = 0.8
    b = (origins * directions).sum(1)
    c = (origins ** 2).sum(1) - radius ** 2
    disc = b * b - c
    analytic_hit = (disc > 0) & (-b - np.sqrt(np.maximum(disc, 0)) > 0)
    clear = np.abs(disc) > 1e-3  # leave out grazing rays
    assert np.array_equal(r.hit[clear], analytic_hit[clear])
    t = -b - np.sqrt(np.maximum(disc, 0))
    exact = origins + directions * t[:, None]
    hits = r.hit & analytic_hit & clear
    assert hits.sum() > 1000
    # a hit stops within epsilon of the surface; along the ray that is epsilon / cos(incidence)
    assert np.abs(np.linalg.norm(r.positions[hits], axis=1) - radius).max() < 1.2e-5
    error = np.linalg.norm(r.positions[hits] - exact[hits], axis=1)
    assert np.median(error) < 1e-5 and error.max() < 1e-3
    normal_error = np.linalg.norm(r.normals[hits] - exact[hits] / radius, axis=1)
    assert normal_error.max() < 1e-3
    assert np.all(r.normals[~r.hit] == 0)


@pytest.mark.parametrize("h, epsilon, relaxation", [((2040.0, 1015.0, 883.0), 1e-4, 1.0), ((1.0, 0.7, 0.5), 1e-7, 0.3)])
def test_an_epsilon_finer_than_float32_at_the_hit_still_hits(h, epsilon, relaxation):
    """A hit distance under t's float32 step (1e-4 in a box 2,000 units long, seed 6 of the cut
    battery; the least epsilon, 1e-7, in a unit box with short steps) is met by a march that
    closes in at a slant: there a step stops moving t, and the march spent its whole budget in
    place and missed (7 and 64 rays of 1,000, as the battery's hole in a solid link; raymarch.glsl
    bm_march, the shaders' copy, ends it as the C++ does). Every ray the link holds a point
    of at least 1/200 of its size deep (core.sdf_distance on 2,000 points along it) hits, its
    position within 2^-22 of the distance travelled of the surface."""
    rng = np.random.default_rng(36)
    h = np.array(h)
    n = 1000
    targets = rng.uniform(-1.0, 1.0, (n, 3)) * h
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    origins = targets - directions * 4.0 * h.max()
    along = np.linspace(0.0, 8.0 * h.max(), 2000)
    points = origins[:, None, :] + along[None, :, None] * directions[:, None, :]
    depth = core.sdf_distance("LINK", points.reshape(-1, 3), h).reshape(n, -1).min(axis=1)
    inside = depth < -5e-3 * h.min()
    assert inside.sum() > 200
    r = core.raymarch(origins, directions, h, sdf="LINK", max_steps=512, epsilon=epsilon, relaxation=relaxation)
    missed = np.flatnonzero(inside & ~r.hit)
    assert not missed.size, f"{missed.size} rays through the link missed (steps {r.steps[missed][:10]})"
    travelled = np.linalg.norm(r.positions[inside] - origins[inside], axis=1)
    reached = np.abs(core.sdf_distance("LINK", r.positions[inside], h))
    assert np.all(reached <= np.maximum(epsilon, 2.4e-7 * travelled / relaxation) + 1e-6 * h.max())


def test_rays_missing_the_box_take_no_steps():
    r = core.raymarch([[0, 5, -5], [0, 0, -5]], [[0, 0, 1], [0, 0, 1]], [1, 1, 1], sdf="SPHERE")
    assert list(r.hit) == [False, True]
    assert r.steps[0] == 0 and r.steps[1] >= 1


def test_ray_stops_where_it_leaves_the_box():
    # passes beside the sphere inside the box: leaves the box after a few steps, no hit
    r = core.raymarch([[0.95, 0.95, -2]], [[0, 0, 1]], [1, 1, 1], sdf="SPHERE", max_steps=1000, epsilon=1e-6)
    assert not r.hit[0] and r.steps[0] < 20
    assert r.positions[0, 2] > 1.0  # the last sample is past the exit face


def test_box_preset_hits_at_entry_in_one_step():
    r = core.raymarch([[0.2, -0.1, -3]], [[0, 0, 1]], [0.5, 0.3, 0.1], sdf="BOX")
    assert r.hit[0] and r.steps[0] == 1
    assert np.allclose(r.positions[0], [0.2, -0.1, -0.1], atol=1e-6)
    assert np.allclose(r.normals[0], [0, 0, -1], atol=1e-4)


def test_step_budget_relaxation_and_max_distance():
    origins = np.array([[0.0, 0.0, -1.0]])
    directions = np.array([[0.05, 0.0, 1.0]])
    full = core.raymarch(origins, directions, [1, 1, 1], sdf="TORUS", max_steps=256, epsilon=1e-5)
    assert full.hit[0]
    none = core.raymarch(origins, directions, [1, 1, 1], sdf="TORUS", max_steps=0)
    assert not none.hit[0] and none.steps[0] == 0
    slow = core.raymarch(origins, directions, [1, 1, 1], sdf="TORUS", max_steps=256, epsilon=1e-5, relaxation=0.5)
    assert slow.hit[0] and slow.steps[0] > full.steps[0]
    assert np.allclose(slow.positions, full.positions, atol=1e-4)
    short = core.raymarch(origins, directions, [1, 1, 1], sdf="TORUS", max_distance=0.1)
    assert not short.hit[0]


@pytest.mark.parametrize("kwargs, message", [
    (dict(epsilon=0.0), "epsilon"), (dict(relaxation=0.0), "relaxation"), (dict(relaxation=2.5), "relaxation"),
    (dict(max_distance=-1.0), "max_distance"), (dict(max_steps=-1), "max_steps"), (dict(sdf="BLOB"), "sdf"),
])
def test_bad_options_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        core.raymarch([[0, 0, -2]], [[0, 0, 1]], [1, 1, 1], **kwargs)


def test_non_finite_input_raises():
    with pytest.raises(ValueError, match="directions holds NaN"):
        core.raymarch([[0, 0, -2]], [[0, np.nan, 1]], [1, 1, 1])
    with pytest.raises(ValueError, match="quaternions holds NaN"):
        core.render_boxes([[0, 0, 0]], [[0, 0, np.inf, 1]], [[1, 1, 1]], np.eye(4), np.eye(4), 8, 8)


def test_bad_shapes_raise():
    with pytest.raises(ValueError, match="directions"):
        core.raymarch(np.zeros((3, 3)), np.zeros((2, 3)), [1, 1, 1])
    with pytest.raises(ValueError, match="half_extents"):
        core.raymarch(np.zeros((3, 3)), np.ones((3, 3)), np.ones((2, 3)))


def perspective(fov_y, aspect, near, far):
    f = 1 / np.tan(fov_y / 2)
    return np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]])


def test_render_box_facing_camera_covers_its_projection():
    # Camera at the origin looking down -z (view = identity); a 2 x 1 x 1 box centred 5 units away.
    width, height = 64, 48
    proj = perspective(np.radians(40), width / height, 0.1, 100.0)
    model = np.eye(4)
    model[:3, 3] = [0, 0, -5]
    image = core.render_boxes([[0, 0, 0]], [[0, 0, 0, 1]], [[1.0, 0.5, 0.5]], proj @ model, model, width, height)
    # front face at z = -4.5: pixel centres whose ray meets |x| <= 1, |y| <= 0.5 there
    xs = ((np.arange(width) + 0.5) / width * 2 - 1) * np.tan(np.radians(20)) * width / height * 4.5
    ys = (1 - (np.arange(height) + 0.5) / height * 2) * np.tan(np.radians(20)) * 4.5
    expected = (np.abs(ys)[:, None] <= 0.5) & (np.abs(xs)[None, :] <= 1.0)
    assert np.array_equal(image.coverage, expected)
    z_ndc = (proj[2, 2] * -4.5 + proj[2, 3]) / 4.5
    assert np.allclose(image.depth[expected], z_ndc * 0.5 + 0.5, atol=1e-6)
    assert np.allclose(image.normals[expected], [0, 0, 1], atol=1e-4)
    assert np.all(image.depth[~expected] == 1.0) and np.all(image.rgba[~expected] == 0.0)


def test_render_baked_mesh_equals_render_of_known_boxes():
    (positions, edges, fs, fz, cv), centres, sizes, rotations = scenes.random_boxes(30, seed=5, spread=3,
                                                                                      size_range=(0.3, 1.5))
    baked = core.bake(positions, edges, fs, fz, cv)
    uv = [np.zeros((len(cv), 2), np.float32) for _ in range(2)]
    for half in range(2):
        core.corner_quaternion_uv(uv[half], half, cv, baked, write_all=True)
    corner_q = np.concatenate(uv, axis=1)
    width, height = 96, 64
    proj = perspective(np.radians(50), width / height, 0.5, 50.0)
    view = np.eye(4)
    view[:3, 3] = [0, 0, -12]
    from_mesh = core.render_baked_mesh(positions, baked.offsets, cv, corner_q, baked.submesh_of_vertex,
                                       proj @ view, view, width, height, sdf="SPHERE", epsilon=1e-5)
    radii = sizes.min(axis=1) / 2
    # ground truth: nearest ray-sphere hit per pixel, in float64
    xs = ((np.arange(width) + 0.5) / width * 2 - 1) / proj[0, 0]
    ys = (1 - (np.arange(height) + 0.5) / height * 2) / proj[1, 1]
    d = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], -1.0), -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    eye = np.array([0, 0, 12.0])
    oc = eye - centres
    b = np.einsum("hwk,nk->hwn", d, oc)
    disc = b * b - ((oc ** 2).sum(1) - radii ** 2)
    t = np.where(disc > 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf).min(-1)
    hit = np.isfinite(t)
    assert hit.mean() > 0.05
    assert (from_mesh.coverage == hit).mean() >= 0.995
    both = from_mesh.coverage & hit
    view_z = -t[both] * -d[both][:, 2]
    z_ndc = (proj[2, 2] * view_z + proj[2, 3]) / -view_z
    # silhouette pixels may take the sphere behind: compare the bulk
    assert np.percentile(np.abs(from_mesh.depth[both] - (z_ndc * 0.5 + 0.5)), 99) < 2e-5


def test_render_box_crossing_the_eye_plane():
    # Camera at the origin looking down -z, 120 degree field; the box reaches from z = -1.5 to
    # z = 0.5, so part of it is behind the eye: the front part must still be drawn in full.
    width, height = 80, 40
    proj = perspective(np.radians(120), width / height, 0.05, 50.0)
    centre, half = np.array([2.0, 0.3, -0.5]), np.array([1.0, 0.8, 1.0])
    image = core.render_boxes([centre], [[0, 0, 0, 1]], [half], proj, np.eye(4), width, height)
    xs = ((np.arange(width) + 0.5) / width * 2 - 1) / proj[0, 0]
    ys = (1 - (np.arange(height) + 0.5) / height * 2) / proj[1, 1]
    d = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], -1.0), -1)
    with np.errstate(divide="ignore"):
        t_lo = ((centre - half) / d)
        t_hi = ((centre + half) / d)
    t_near = np.minimum(t_lo, t_hi).max(-1)
    t_far = np.maximum(t_lo, t_hi).min(-1)
    expected = (t_far >= np.maximum(t_near, 0.05)) & (t_far > 0.05)
    assert expected.mean() > 0.1
    assert (image.coverage == expected).mean() >= 0.995

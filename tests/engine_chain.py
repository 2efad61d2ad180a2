"""A short chain of link boxes whose geometry the tests know (centres, sizes, rotations chosen here),
and what a chain link drawn in each box must cover, raymarched in float64 from that geometry alone
(not from the bake, the export or the shaders under test). Blender-free."""
import numpy as np

# Link length, width and wire thickness: a link sized by its box (docs/PREVIEW.md, LINK) is
# stretched along the box's longest side, its ring across the middle one, its wire along the
# shortest.
LINK = np.array([1.0, 0.5, 0.12])
ARC_RADIUS, LINK_COUNT = 3.0, 6


def chain_links():
    """(centres, sizes, rotations) of LINK_COUNT links on an arc in Blender's x-z plane, each
    turned 90 degrees about its own axis from the last (a chain). Rotation columns are the link's
    length, width and thickness axes in that order, which is not the order the default bake gives
    the box's local axes (it starts from the shortest side here)."""
    step = 0.78 * LINK[0] / ARC_RADIUS
    angles = step * (np.arange(LINK_COUNT) - (LINK_COUNT - 1) / 2)
    centres = np.column_stack([ARC_RADIUS * np.sin(angles), np.zeros(LINK_COUNT), ARC_RADIUS * np.cos(angles)])
    tangent = np.column_stack([np.cos(angles), np.zeros(LINK_COUNT), -np.sin(angles)])
    radial = centres / ARC_RADIUS
    facing = np.tile([0.0, 1.0, 0.0], (LINK_COUNT, 1))  # ring in the arc's plane: seen flat from -y
    across = np.where((np.arange(LINK_COUNT) % 2)[:, None] == 0, facing, radial)
    rotations = np.stack([tangent, np.cross(across, tangent), across], axis=2)
    return centres, np.tile(LINK, (LINK_COUNT, 1)), rotations


def link_distance(local, half):
    """Signed distance from box-local points (n, 3) (axes: length, width, thickness) to the link
    filling a box of half-extents ``half`` (length >= width >= thickness): a ring of tube radius
    t = min(thickness, width / 4) whose centre line is a stadium, straight for length - width
    along the first axis, with semicircles of radius width - t in the first two axes' plane."""
    t = min(half[2], 0.25 * half[1])
    straight = np.maximum(np.abs(local[:, 0]) - (half[0] - half[1]), 0.0)
    in_plane = np.hypot(straight, local[:, 1]) - (half[1] - t)
    return np.hypot(in_plane, local[:, 2]) - t


def pixel_rays(shot):
    """(origin (3,), directions (H, W, 3) unit) of the rays through the pixel centres of ``shot``,
    from its 3x4 world -> pixel matrix (any pinhole camera)."""
    height, width = shot.pixels.shape[:2]
    m, last = shot.to_pixels[:, :3], shot.to_pixels[:, 3]
    eye = -np.linalg.solve(m, last)
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    d = np.stack([xs, ys, np.ones_like(xs)], axis=2) @ np.linalg.inv(m).T
    return eye, d / np.linalg.norm(d, axis=2, keepdims=True)


def link_coverage(shot, centres, sizes, rotations, to_engine, steps=400, epsilon=1e-5):
    """(H, W) boolean: the pixels of ``shot``'s image whose centre ray hits one of the links in the
    boxes (Blender frame; ``to_engine`` maps it to the shot's world), sphere-traced in float64
    inside each box (a hit: the distance falls below ``epsilon`` x the box's length)."""
    eye, directions = pixel_rays(shot)
    hit = np.zeros(directions.shape[:2], bool)
    for centre, size, rotation in zip(centres, sizes, rotations):
        order = np.argsort(-np.asarray(size), kind="stable")  # length, width, thickness
        axes = to_engine @ np.asarray(rotation)[:, order]
        half = np.asarray(size, float)[order] / 2
        ro = (eye - to_engine @ centre) @ axes
        rd = directions.reshape(-1, 3) @ axes
        with np.errstate(divide="ignore", invalid="ignore"):
            t0, t1 = (-half - ro) / rd, (half - ro) / rd
        near = np.nan_to_num(np.minimum(t0, t1), nan=-np.inf).max(axis=1)
        far = np.nan_to_num(np.maximum(t0, t1), nan=np.inf).min(axis=1)
        rays = np.flatnonzero(far > np.maximum(near, 0.0))
        t = np.maximum(near[rays], 0.0)
        found = np.zeros(len(rays), bool)
        for _ in range(steps):
            d = link_distance(ro + rd[rays] * t[:, None], half)
            found |= d < epsilon * half[0]
            t = np.where(found, t, t + d)
            if np.all(found | (t > far[rays])):
                break
        hit.reshape(-1)[rays[found & (t <= far[rays])]] = True
    return hit

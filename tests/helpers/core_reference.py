"""Reference maths the core tests check against, written from the specification (quaternion
algebra, bounds, the frame rule) without going through the code under test, and small meshes
built by hand. Shared by test_core.py and test_core_properties.py."""
from __future__ import annotations

import numpy as np

from boxmarch import core

U32 = 2.0 ** -24  # float32 unit roundoff: a stored coordinate x is within |x| * U32 of its value
TIE_BAND = 1e-3  # relative band inside which face areas (edge lengths) tie; lowest index wins
FACES = core.FRAME_SOURCES.index("FACES")


# -------------------------------------------------------------------------------------------------
# Independent maths


def quat_matrix(q):
    """(..., 3, 3) rotation matrices of quaternions (x, y, z, w), normalised in float64 first, so
    the result is orthonormal to float64 precision. Column i is local axis i in object space."""
    q = np.asarray(q, np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def shader_rotate(v, q):
    """The documented shader formula, with q used as stored: v + 2 u x (u x v + w v)."""
    v = np.asarray(v, np.float64)
    q = np.asarray(q, np.float64)
    u = q[..., :3]
    return v + 2.0 * np.cross(u, np.cross(u, v) + q[..., 3:4] * v)


def decode_rgba(rgba):
    """f = (rgb * 2 - 1) / a in float64; bytes are divided by 255 first."""
    rgba = np.asarray(rgba)
    c = rgba.astype(np.float64)
    if rgba.dtype == np.uint8:
        c = c / 255.0
    return (c[..., :3] * 2.0 - 1.0) / c[..., 3:4]


def decoded_origins(r, positions):
    """Per vertex: the origin a shader reconstructs from the vertex's own stored data."""
    q = r.quaternions[r.submesh_of_vertex]
    return positions.astype(np.float64) + shader_rotate(decode_rgba(r.offsets), q)


def bounds_centre(points, frame):
    """Object-space centre of the bounding box of points (float64) measured in frame (columns =
    orthonormal axes), computed relative to the first point to keep far points precise."""
    base = points[0]
    local = (points - base) @ frame
    return base + frame @ (0.5 * (local.min(0) + local.max(0)))


def half_extents_in(points, frame):
    local = points @ frame
    return 0.5 * (local.max(0) - local.min(0))


def vertices_of(r, s):
    return np.flatnonzero(r.submesh_of_vertex == s)


def assert_frames_valid(r):
    """Stored quaternions are unit, w >= 0, and give orthonormal right-handed frames."""
    q = r.quaternions.astype(np.float64)
    assert np.all(np.isfinite(q))
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    assert np.all(q[:, 3] >= 0.0)
    m = quat_matrix(q)
    identity = np.broadcast_to(np.eye(3), m.shape)
    np.testing.assert_allclose(m.transpose(0, 2, 1) @ m, identity, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(m), 1.0, atol=1e-12)


def axis_angles(a, b):
    """Angle (radians) between the lines of unit vectors a and b (sign ignored)."""
    return np.arccos(np.clip(np.abs(np.sum(a * b, -1)), 0.0, 1.0))


def distinct_sizes(rng, n, lo, hi):
    """(n, 3) box sizes whose three values differ pairwise by a factor >= 1.15 (far from any tie)
    and whose largest value is log-uniform in [lo, hi], in random axis order."""
    largest = np.exp(rng.uniform(np.log(lo), np.log(hi), n))
    ratios = rng.uniform(1.15, 2.0, (n, 2))
    sizes = np.stack([largest, largest / ratios[:, 0], largest / ratios[:, 0] / ratios[:, 1]], 1)
    return np.take_along_axis(sizes, rng.permuted(np.tile([0, 1, 2], (n, 1)), axis=1), 1)


# -------------------------------------------------------------------------------------------------
# Hand-built meshes


def mesh_from_polys(polys):
    """Mesh arrays from a list of (points (n, 3), faces [[v, ...], ...], extra_edges [(a, b), ...]).
    Each face contributes its boundary edges (first-seen direction kept); vertices are indexed per
    piece. Positions are rounded once to float32."""
    pos, edges, starts, sizes, corners = [], [], [], [], []
    base = 0
    for piece in polys:
        points, faces = piece[0], piece[1]
        extra = piece[2] if len(piece) > 2 else []
        seen = set()
        for f in faces:
            starts.append(len(corners))
            sizes.append(len(f))
            corners.extend(base + v for v in f)
            for a, b in zip(f, f[1:] + f[:1]):
                if (a, b) not in seen and (b, a) not in seen:
                    seen.add((a, b))
                    edges.append((base + a, base + b))
        for a, b in extra:
            edges.append((base + a, base + b))
        pos.append(np.asarray(points, np.float64).reshape(-1, 3))
        base += len(pos[-1])
    return (np.concatenate(pos).astype(np.float32), np.array(edges, np.int32).reshape(-1, 2),
            np.array(starts, np.int32), np.array(sizes, np.int32), np.array(corners, np.int32))


def wedge():
    """Right-triangle prism: one clear largest face (the slanted one), a clear runner-up."""
    a, b, length = 1.0, 0.6, 2.3
    points = [[0, 0, 0], [a, 0, 0], [0, b, 0], [0, 0, length], [a, 0, length], [0, b, length]]
    faces = [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]]
    return np.array(points, float), faces


def house():
    """Box 2 x 1.4 x 1 whose top is an off-centre pyramid: chiral (no mirror symmetry)."""
    box = np.array([[x, y, z] for z in (0.0, 1.0) for y in (-0.7, 0.7) for x in (-1.0, 1.0)])
    points = np.vstack([box, [[0.3, 0.2, 1.35]]])
    faces = [[0, 2, 3, 1], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5],
             [4, 5, 8], [5, 7, 8], [7, 6, 8], [6, 4, 8]]
    return points, faces


def flat_polygon():
    """Irregular planar octagon (its frame comes from the face normal and its longest edge)."""
    angles = 2 * np.pi * np.arange(8) / 8 + np.array([0, .05, -.04, .03, 0, -.06, .02, .04])
    radii = np.array([1.0, 1.05, 0.97, 1.02, 0.99, 1.04, 0.96, 1.01])
    points = np.stack([radii * np.cos(angles), radii * np.sin(angles), np.zeros(8)], 1)
    return points, [list(range(8))]


def newell(points, face):
    """Unit Newell normal and area of a polygon."""
    p = points[face] - points[face[0]]
    s = np.sum(np.cross(p, np.roll(p, -1, 0)), 0)
    length = np.linalg.norm(s)
    return s / length, 0.5 * length


def pick_largest(sizes, eligible):
    """Lowest eligible index within the tie band of the largest eligible size. Refuses geometry
    whose outcome would hinge on rounding (a size right at the band's edge)."""
    best = sizes[eligible].max()
    cut = (1.0 - TIE_BAND) * best
    near = eligible & (np.abs(sizes - cut) < 2e-4 * best)
    assert not near.any(), "test geometry is ambiguous at the tie band's edge"
    return int(np.flatnonzero(eligible & (sizes >= cut))[0])


def reference_frame(points, faces, edges=None, angle_epsilon=0.1):
    """The spec's frame rule in float64: axis 1 = normal of the largest face, axis 2 = normal of
    the largest face more than angle_epsilon off axis 1 (or, when no face is, the longest such
    edge), made orthogonal; axis 3 = axis 1 x axis 2."""
    points = np.asarray(points, np.float64)
    normals, areas = map(np.array, zip(*(newell(points, f) for f in faces)))
    cos_eps = np.cos(angle_epsilon)
    x = normals[pick_largest(areas, np.ones(len(faces), bool))]
    eligible = np.abs(normals @ x) < cos_eps
    if eligible.any():
        d = normals[pick_largest(areas, eligible)]
    else:
        vec = points[edges[:, 1]] - points[edges[:, 0]]
        lengths = np.linalg.norm(vec, axis=1)
        vec = vec / lengths[:, None]
        d = vec[pick_largest(lengths, np.abs(vec @ x) < cos_eps)]
    y = d - (d @ x) * x
    y /= np.linalg.norm(y)
    return np.stack([x, y, np.cross(x, y)], 1)


def similar_copy(points, rotation, scale, shift):
    return np.asarray(points, np.float64) @ np.asarray(rotation).T * scale + shift

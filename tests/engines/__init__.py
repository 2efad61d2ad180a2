"""Harnesses that load files into real engines and report what the engine received and drew.

``threejs`` runs three.js r111 (Debian's libjs-three, WebGL 1) and r180 (NiceGUI's ES module
build, WebGL 2) in headless Chromium on SwiftShader;
``godot3`` runs Debian's Godot 3.2 (headless import, rendering under xvfb on llvmpipe). Neither
imports Blender. Both ``render`` functions return a :class:`Shot`, and :func:`coverage_mismatch`
checks drawn pixels against polygons projected with the engine's own camera.
"""
from typing import NamedTuple, Optional

import numpy as np


class Shot(NamedTuple):
    """One rendered frame and the camera the engine used for it.

    ``pixels``: (H, W, 4) uint8 RGBA, row 0 = top of the image.
    ``view``: 4x4 world -> camera matrix as the engine computed it.
    ``to_pixels``: 3x4 world -> homogeneous pixel matrix derived from the engine's own camera:
    x grows right, y grows down, (0, 0) is the top-left corner of the image, so pixel (i, j) has
    its centre at (j + 0.5, i + 0.5).
    """

    pixels: np.ndarray
    view: np.ndarray
    to_pixels: np.ndarray

    def project(self, points) -> np.ndarray:
        """(N, 2) pixel coordinates (x right, y down) of (N, 3) world points."""
        p = np.asarray(points, dtype=np.float64)
        h = np.c_[p, np.ones(len(p))] @ self.to_pixels.T
        return h[:, :2] / h[:, 2:3]


def ndc_to_pixels(width, height) -> np.ndarray:
    """3 x 4 map from GL clip coordinates to homogeneous pixel coordinates (x right, y down,
    (0, 0) the top-left corner): ``Shot.to_pixels`` = this @ projection @ view."""
    return np.array([[width / 2, 0, 0, width / 2], [0, -height / 2, 0, height / 2], [0, 0, 0, 1.0]])


def perspective(camera, aspect) -> np.ndarray:
    """4 x 4 OpenGL perspective projection of a harness ``camera`` (vertical ``fov`` in degrees,
    ``near``, ``far``) for a ``aspect`` = width / height image."""
    f = 1.0 / np.tan(np.radians(camera["fov"]) / 2)
    near, far = camera["near"], camera["far"]
    return np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]])


def view_matrix(camera) -> np.ndarray:
    """4 x 4 view matrix of a harness ``camera`` (``position``, ``target``, ``up``), as three.js's
    ``lookAt`` makes it: the camera looks down its -z, ``up`` kept in its yz plane."""
    eye, target = np.asarray(camera["position"], np.float64), np.asarray(camera["target"], np.float64)
    back = (eye - target) / np.linalg.norm(eye - target)
    right = np.cross(camera.get("up", (0.0, 1.0, 0.0)), back)
    right /= np.linalg.norm(right)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, np.cross(back, right), back])
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def polygon_mask(shape, polygon) -> np.ndarray:
    """Boolean (H, W) mask of the pixels whose centres lie inside a convex 2D ``polygon``
    (pixel coordinates as :meth:`Shot.project` returns them, either winding)."""
    poly = np.asarray(polygon, dtype=np.float64)
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]] + 0.5
    sides = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        sides.append((b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0]))
    sides = np.array(sides)
    return np.all(sides >= 0, axis=0) | np.all(sides <= 0, axis=0)


def _grow(mask, n):
    """``mask`` dilated by n pixels (3x3 square steps)."""
    for _ in range(n):
        p = np.pad(mask, 1)
        mask = np.zeros_like(mask)
        for dy in range(3):
            for dx in range(3):
                mask |= p[dy : dy + mask.shape[0], dx : dx + mask.shape[1]]
    return mask


def mask_errors(covered, expected, tol: int = 1):
    """(stray, missing) (H, W) boolean masks: ``covered`` pixels farther than ``tol`` px from
    every ``expected`` pixel, and uncovered pixels deeper than ``tol`` px inside ``expected``."""
    covered, expected = np.asarray(covered, dtype=bool), np.asarray(expected, dtype=bool)
    return covered & ~_grow(expected, tol), ~covered & ~_grow(~expected, tol)


def coverage_errors(covered, polygons, tol: int = 1):
    """:func:`mask_errors` against the union of convex pixel-space ``polygons``."""
    expected = np.zeros(np.shape(covered), dtype=bool)
    for poly in polygons:
        expected |= polygon_mask(expected.shape, poly)
    return mask_errors(covered, expected, tol)


def coverage_mismatch(covered, polygons, tol: int = 1) -> Optional[str]:
    """None when the (H, W) boolean ``covered`` mask equals the union of the convex pixel-space
    ``polygons`` up to ``tol`` pixels at every edge; else a message saying where it differs.

    Every covered pixel must lie within ``tol`` px of a polygon, and every pixel deeper than
    ``tol`` px inside one must be covered, so a shape drawn ``tol + 1`` px off fails.
    """
    return _mismatch_message(*coverage_errors(covered, polygons, tol))


def mask_mismatch(covered, expected, tol: int = 1) -> Optional[str]:
    """:func:`coverage_mismatch` against an expected (H, W) boolean mask (a reference render)."""
    return _mismatch_message(*mask_errors(covered, expected, tol))


def _mismatch_message(stray, missing) -> Optional[str]:
    if not stray.any() and not missing.any():
        return None
    msg = []
    for name, bad in (("covered outside", stray), ("uncovered inside", missing)):
        if bad.any():
            ys, xs = np.nonzero(bad)
            msg.append(f"{len(ys)} px {name} the expected shapes, rows {ys.min()}..{ys.max()}, "
                       f"columns {xs.min()}..{xs.max()}")
    return "; ".join(msg)


def tightest_tolerance(covered, polygons, limit: int = 64) -> int:
    """Smallest tolerance in px at which ``covered`` matches ``polygons`` (limit + 1: none):
    what the benchmarks print beside each render check."""
    for tol in range(limit + 1):
        stray, missing = coverage_errors(covered, polygons, tol)
        if not stray.any() and not missing.any():
            return tol
    return limit + 1


def segment_errors(drawn, segments, tol: float = 1.5, shortest: float = 2.0):
    """(stray, missed) for lines an engine drew against the pixel-space ``segments`` ((N, 2, 2):
    start and end, as :meth:`Shot.project` returns them) they should be: ``stray`` the drawn
    pixels whose centres lie farther than ``tol`` px from every segment; ``missed`` the points,
    every half pixel along each segment longer than ``shortest`` px (a shorter line may rasterise
    to nothing), inside the image and with no drawn pixel within ``tol`` px (centre to point,
    largest coordinate difference), so a line that stops short or bends away misses them."""
    drawn = np.asarray(drawn, dtype=bool)
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)
    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    ys, xs = np.nonzero(drawn)
    centres = np.c_[xs, ys] + 0.5
    stray = 0
    for chunk in np.array_split(centres, max(1, len(centres) // 4096)):
        rel = chunk[:, None, :] - a[None]
        t = np.clip(np.einsum("nsk,sk->ns", rel, d) / np.maximum(np.einsum("sk,sk->s", d, d), 1e-12), 0.0, 1.0)
        gap = np.linalg.norm(rel - t[..., None] * d[None], axis=2).min(axis=1)
        stray += int((gap > tol).sum())
    reach = int(np.ceil(tol))
    padded = np.pad(drawn, reach)
    missed = 0
    for start, step in zip(a, d):
        length = np.linalg.norm(step)
        if length <= shortest:
            continue
        points = start + np.linspace(0.0, 1.0, int(2 * length) + 1)[:, None] * step
        inside = (points[:, 0] >= 0) & (points[:, 1] >= 0) & (points[:, 0] < drawn.shape[1]) & (points[:, 1] < drawn.shape[0])
        for x, y in points[inside]:
            column, row = int(x), int(y)  # padded[row + reach, column + reach] is pixel (row, column)
            wy, wx = np.nonzero(padded[row : row + 2 * reach + 1, column : column + 2 * reach + 1])
            near = np.maximum(np.abs(column - reach + wx + 0.5 - x), np.abs(row - reach + wy + 0.5 - y))
            missed += not (near <= tol).any()
    return stray, missed

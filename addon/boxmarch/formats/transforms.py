"""Format-facing transforms of the baked data: what each engine preset writes so the file holds
the final numbers for the documented decode (docs/FORMAT.md) in the target's object frame.

Blender-free (NumPy only), like the format half of glTF-Blender-IO; ``export/scene.py`` is the
Blender-facing half. docs/EXPORT.md derives every transform here.

A preset is described by a rotation and a mirror, as signed permutation matrices:

* ``rotation`` A0 (det +1) and ``mirror`` N (diagonal, +-1): target object coordinates of a
  Blender object-space point are p' = A p with A = N A0, as the exporter (and, for Unity, the
  engine's importer) converts positions;
* when N is a reflection no rotation maps Blender's frame to the target's, so each box's local
  frame is mirrored the way the target mirrors every object frame: local coordinates f' = N f.

Decode invariant: origin' = p' + R(q') f' must equal A (p + R(q) f) for every vertex. With
R(q') = N A0 R(q) N and f' = N f it does, because N N = I; and N Q N is a rotation for any
rotation Q, whose quaternion is Q's with the vector part v replaced by det(N) N v.
"""
from __future__ import annotations

import numpy as np

from .layouts import quaternion_matrices
from .presets import Preset


def matrix_quaternions(m) -> np.ndarray:
    """(n, 4) unit quaternions (x, y, z, w) of rotation matrices, float64, in the baked sign
    convention: w >= 0, and at w = 0 the first nonzero of x, y, z positive. Each row is computed
    from the largest of w, x, y, z (Shepperd's method), so no branch divides by a small number."""
    m = np.asarray(m, np.float64).reshape(-1, 3, 3)
    t = np.stack([m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2], -m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2],
                  -m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2], m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]], 1)
    pick = np.argmax(t, axis=1)
    q = np.empty((len(m), 4))
    s = np.sqrt(np.maximum(1.0 + t[np.arange(len(m)), pick], 0.0)) * 2.0  # 4 * |largest component|
    a, b, c = (m[:, 2, 1] - m[:, 1, 2]), (m[:, 0, 2] - m[:, 2, 0]), (m[:, 1, 0] - m[:, 0, 1])
    d, e, f = (m[:, 0, 1] + m[:, 1, 0]), (m[:, 0, 2] + m[:, 2, 0]), (m[:, 1, 2] + m[:, 2, 1])
    rows = {0: (0.25 * s, d / s, e / s, a / s), 1: (d / s, 0.25 * s, f / s, b / s),
            2: (e / s, f / s, 0.25 * s, c / s), 3: (a / s, b / s, c / s, 0.25 * s)}
    for k, (qx, qy, qz, qw) in rows.items():
        sel = pick == k
        q[sel] = np.stack([qx[sel], qy[sel], qz[sel], qw[sel]], 1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return canonical_sign(q)


def canonical_sign(q) -> np.ndarray:
    """q or -q, whichever has w > 0 (at w = 0: the first nonzero of x, y, z positive)."""
    q = np.array(q, np.float64).reshape(-1, 4)
    lead = np.where(q[:, 3] != 0, q[:, 3],
                    np.where(q[:, 0] != 0, q[:, 0], np.where(q[:, 1] != 0, q[:, 1], q[:, 2])))
    q[lead < 0] *= -1.0
    return q


def multiply(a, b) -> np.ndarray:
    """Hamilton products a b of quaternions (x, y, z, w), broadcast, float64."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    av, aw, bv, bw = a[..., :3], a[..., 3:], b[..., :3], b[..., 3:]
    return np.concatenate([aw * bv + bw * av + np.cross(av, bv),
                           aw * bw - np.sum(av * bv, axis=-1, keepdims=True)], axis=-1)


def target_quaternions(q, preset: Preset) -> np.ndarray:
    """(n, 4) float64: q' with R(q') = N A0 R(q) N, the box frame in the target's object frame,
    in the baked sign convention."""
    turned = multiply(matrix_quaternions(preset.rotation)[0], np.asarray(q, np.float64).reshape(-1, 4))
    if (preset.mirror < 0).any():  # N Q N: vector part v -> det(N) N v = -N v
        turned[:, :3] *= -preset.mirror
    return canonical_sign(turned)


def target_offsets(rgba, preset: Preset) -> np.ndarray:
    """(n, 4) float32 CLASSIC offset colours for the target: f' = N f, so a mirrored channel c
    becomes 1 - c (the encoding 0.5 + 0.5 s f is symmetric about 0.5); positions the importer
    scales by the preset's length scale L scale f too, which the alpha s absorbs: s' = s / L.
    ``rgba`` is float (values as the shader reads them: bytes already divided by 255)."""
    out = np.array(rgba, np.float64).reshape(-1, 4)
    mirrored = preset.mirror < 0
    out[:, :3][:, mirrored] = 1.0 - out[:, :3][:, mirrored]
    out[:, 3] /= preset.length_scale
    return out.astype(np.float32)


def uv_in_file(uv, preset: Preset) -> np.ndarray:
    """(n, 2) float32 UVs to write so that the engine's importer reads ``uv``: Unreal's FBX
    importer reads 1 - v, so the file holds 1 - v (round-off: half an ulp of 1 - v)."""
    out = np.array(uv, np.float64).reshape(-1, 2)
    if preset.flip_v_on_import:
        out[:, 1] = 1.0 - out[:, 1]
    return out.astype(np.float32)


def target_positions(positions, preset: Preset) -> np.ndarray:
    """(n, 3) float64: where the target's object frame puts Blender object-space points."""
    return np.asarray(positions, np.float64) @ preset.axes.T * preset.length_scale


def target_local(vectors, preset: Preset) -> np.ndarray:
    """(n, 3) float64 box-local vectors (offsets f) in the target's local convention: f' = N f L."""
    return np.asarray(vectors, np.float64) * preset.mirror * preset.length_scale


# Boxes whose axes, carried by a linear map, leave a cosine above this between two of them are
# sheared: no box frame decodes them.
SHEAR_COSINE = 1e-5


def frames_in_space(q, f, box_half, box_of_vertex, linear):
    """The box data of a mesh whose positions are written as ``linear`` p (+ a translation): the
    space a skinned glTF file holds (world) differs from the object's. A box's local axis
    R(q) e_i becomes c_i = linear R(q) e_i: the frame is the c_i / |c_i| (the third negated where
    ``linear`` mirrors, so the frame stays a rotation), offsets and half-extents scale by |c_i|
    (with that sign on the offset), and origin' = linear origin exactly. ``q`` (n, 4) and ``f``
    (n, 3) per vertex, ``box_half`` (boxes, 3), ``box_of_vertex`` (n,) ids, ``linear`` (3, 3).
    Returns (q' (n, 4) in the baked sign convention, f' (n, 3), half-extents' (boxes, 3), the
    number of boxes the map shears: a non-uniform scale across a box's axes makes it a
    parallelepiped, which no frame decodes; their values are not meaningful)."""
    linear = np.asarray(linear, np.float64)
    columns = linear @ quaternion_matrices(q)  # column i = c_i
    lengths = np.linalg.norm(columns, axis=1)  # (n, 3)
    unit = columns / np.maximum(lengths, 1e-300)[:, None, :]
    cosines = np.abs(np.einsum("nki,nkj->nij", unit, unit)) - np.eye(3)
    sheared_vertex = cosines.max(axis=(1, 2)) > SHEAR_COSINE if len(unit) else np.zeros(0, bool)
    sign = np.array([1.0, 1.0, -1.0 if np.linalg.det(linear) < 0 else 1.0])
    unit = unit * sign
    box_lengths = np.zeros((len(box_half), 3))
    box_lengths[box_of_vertex] = lengths
    sheared = np.zeros(len(box_half), bool)
    sheared[box_of_vertex[sheared_vertex]] = True
    return (matrix_quaternions(unit), np.asarray(f, np.float64) * lengths * sign,
            np.asarray(box_half, np.float64) * box_lengths, int(sheared.sum()))

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

from dataclasses import dataclass

import numpy as np

from ..layouts import quaternion_matrices


# Blender's Z-up right-handed object space to the Y-up right-handed space of glTF and of FBX
# written with axis_forward='-Z', axis_up='Y': (x, y, z) -> (x, z, -y).
Z_UP_TO_Y_UP = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], np.float64)
# Unity's FBX importer turns the right-handed file into its left-handed frame by negating x:
# the UNITY preset's mirror is diag(-1, 1, 1). Unreal's converts any FBX back to Blender's Z-up
# axes, then negates y into its left-handed frame and scales metres to centimetres: whatever the
# exporter's axis options, Unreal's object frame is (x, -y, z) * 100 of Blender's.


@dataclass(frozen=True)
class Preset:
    name: str
    label: str
    extension: str
    rotation: np.ndarray   # A0 (3, 3), det +1
    mirror: np.ndarray     # diagonal of N (3,), +-1, at most one -1
    description: str
    layouts: tuple = ("CLASSIC",)  # layouts.py names this target can carry; the first is the default
    length_scale: float = 1.0      # the importer's unit conversion of positions (Unreal: metres to cm)
    flip_v_on_import: bool = False  # the importer reads v as 1 - v (Unreal's FBX importer)
    import_settings: str = ""      # what the engine's importer must be told so the data stays float32
    half_float_uvs: tuple = ()     # UV channels the engine stores as half floats unless told otherwise
    godot3_compression: bool = False  # the importer's default mesh compression (Godot 3) quantizes colour and frame
    default_import_loss: str = ""  # what the default import settings do to the data, for the report
    import_fix: str = ""           # the import setting that keeps the data float32, in a few words

    @property
    def axes(self) -> np.ndarray:
        """A = N A0: p' = A p."""
        return self.mirror[:, None] * self.rotation


PRESETS = {
    "GLTF": Preset(
        "GLTF", "glTF Binary", ".glb", Z_UP_TO_Y_UP, np.ones(3),
        "glTF binary for three.js, Godot 4, Babylon: right-handed Y-up, frame in NORMAL + TANGENT",
        layouts=("NORMAL_FRAME", "UV_FRAME", "CLASSIC"),
        import_settings="three.js and Babylon: none. Godot 4: Mesh Compression off in the scene import "
                        "(Godot 4 stores vertex colours as 8 bits: the default layout uses none)"),
    "GODOT3": Preset(
        "GODOT3", "Godot 3 (glTF + box table)", ".glb", Z_UP_TO_Y_UP, np.ones(3),
        "glTF binary for Godot 3's importer (two UV sets): frame in NORMAL + TANGENT, offset and index in a "
        "float colour, half-extents in a .tres float texture beside it",
        layouts=("NORMAL_COLOR",), godot3_compression=True,
        default_import_loss="mesh compression: 8-bit colour clamped to [0, 1], 8-bit normal and tangent",
        import_fix="copy NAME.glb.import (written beside) with the .glb, or in the Import dock Meshes > Compress off",
        import_settings="Import dock of the .glb: Meshes > Compress off (else colour is 8-bit and normals, "
                        "tangents and UV2 are packed): the NAME.glb.import written beside it sets this when copied "
                        "with it, or the boxmarch plug-in (engines/godot3) does; keep the .boxes.tres beside it and "
                        "assign it to the shader's box_table"),
    "UNITY": Preset(
        "UNITY", "Unity (FBX)", ".fbx", Z_UP_TO_Y_UP, np.array([-1.0, 1.0, 1.0]),
        "FBX for Unity's importer: left-handed Y-up object frame, box data in float UV channels "
        "(skinned meshes: frame in NORMAL + TANGENT)",
        layouts=("UV_FRAME", "CLASSIC", "NORMAL_FRAME"),
        import_settings="Model import: Read/Write on (or Player > Vertex Compression: untick Tex Coord 2-7), "
                        "Mesh Compression Off; UV_FRAME needs no vertex colour; NORMAL_FRAME (skinned meshes): Normals "
                        "Import, Tangents Import (their frame is the box's)",
        half_float_uvs=(2, 3, 4, 5, 6), default_import_loss="vertex compression: half-float UV2-UV6",
        import_fix="engines/unity's postprocessor sets it, or in the model import Read/Write on"),
    "UNREAL": Preset(
        "UNREAL", "Unreal (FBX)", ".fbx", np.eye(3), np.array([1.0, -1.0, 1.0]),
        "FBX for Unreal's importer: left-handed Z-up centimetres (y mirrored), V flipped, box data in float UVs",
        layouts=("UV_FRAME",), length_scale=100.0, flip_v_on_import=True,
        import_settings="Static mesh import: Use Full Precision UVs on (else UVs are 16-bit halves), "
                        "Generate Lightmap UVs off (it writes into UV channel 1), Convert Scene on (default)",
        half_float_uvs=(1, 2, 3, 4, 5, 6), default_import_loss="16-bit half-float UVs",
        import_fix="import with engines/unreal/boxmarch_import.py, or Use Full Precision UVs on"),
    "BLENDER": Preset(
        "BLENDER", "Blender (raw)", ".blend", np.eye(3), np.ones(3),
        "The selected objects in a .blend, baked data in Blender's own object space"),
}


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

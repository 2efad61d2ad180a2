"""Engine presets: one :class:`Preset` per target engine, holding every fact the add-on knows
about it: axes and units (the transform ``formats/transforms.py`` applies), the layouts it can
carry, what its importer does to the data by default and the settings that keep them float32
(``formats/import_settings.py`` holds the settings tables the engine helpers are tested against),
the frames the sidecar names, and the engine-side helper shipped in ``engines/``.

Adding a preset is one entry in :data:`PRESETS` plus tests (CONTRIBUTING.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import import_settings

# Blender's Z-up right-handed object space to the Y-up right-handed space of glTF and of FBX
# written with axis_forward='-Z', axis_up='Y': (x, y, z) -> (x, z, -y).
Z_UP_TO_Y_UP = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], np.float64)
# Unity's FBX importer turns the right-handed file into its left-handed frame by negating x:
# the UNITY preset's mirror is diag(-1, 1, 1). Unreal's converts any FBX back to Blender's Z-up
# axes, then negates y into its left-handed frame and scales metres to centimetres: whatever the
# exporter's axis options, Unreal's object frame is (x, -y, z) * 100 of Blender's.


# Frames as the sidecar names them: Blender's object space, the glTF / FBX files (both written
# right-handed Y-up in metres) and the engines' object frames the box data are expressed in.
_BLENDER = {"up": "+Z", "handedness": "right", "units": "metre"}
_Y_UP = {"up": "+Y", "handedness": "right", "units": "metre"}


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
    colour_8bit: bool = False      # the engine usually stores vertex colours as 8 bits (Unity's Color32)
    data_frame: dict = field(default_factory=lambda: dict(_Y_UP))  # the engine's object frame of the box data
    engine_settings: dict = field(default_factory=dict)  # the sidecar's settings tables (import_settings)
    helper: str | None = None      # the engine-side helper, relative to the repository (docs/ENGINES.md)

    @property
    def axes(self) -> np.ndarray:
        """A = N A0: p' = A p."""
        return self.mirror[:, None] * self.rotation

    @property
    def raw_blend(self) -> bool:
        """The .blend holds the baked layers as they are: no engine transform, no box table."""
        return self.extension == ".blend"

    @property
    def file_from_blender(self) -> np.ndarray:
        """(3, 3): Blender's axes to the file's (glTF and FBX are written Y-up, a .blend as is)."""
        return np.eye(3) if self.raw_blend else Z_UP_TO_Y_UP

    @property
    def file_frame(self) -> dict:
        """The frame positions are written in, as the sidecar names it."""
        return dict(_BLENDER if self.raw_blend else _Y_UP)

    @property
    def writes_godot3_import(self) -> bool:
        """An export writes ``NAME.glb.import`` beside the file (compression off when Godot 3 imports it)."""
        return self.godot3_compression


PRESETS = {
    "GLTF": Preset(
        "GLTF", "glTF Binary", ".glb", Z_UP_TO_Y_UP, np.ones(3),
        "glTF binary for three.js, Godot 4, Babylon: right-handed Y-up, frame in NORMAL + TANGENT",
        layouts=("NORMAL_FRAME", "UV_FRAME", "CLASSIC"),
        import_settings="three.js and Babylon: none. Godot 4: Mesh Compression off in the scene import "
                        "(Godot 4 stores vertex colours as 8 bits: the default layout uses none)",
        helper="shaders/threejs"),
    "GODOT3": Preset(
        "GODOT3", "Godot 3 (glTF + box table)", ".glb", Z_UP_TO_Y_UP, np.ones(3),
        "glTF binary for Godot 3's importer (two UV sets): frame in NORMAL + TANGENT, offset and index in a "
        "float colour, half-extents in a .tres float texture beside it",
        layouts=("NORMAL_COLOR",), godot3_compression=True,
        default_import_loss="mesh compression: 8-bit colour clamped to [0, 1], 8-bit normal and tangent",
        import_fix="copy NAME.glb.import (written beside) with the .glb, or in the Import dock Meshes > Compress off",
        engine_settings={"godot3_scene_import": import_settings.GODOT3}, helper="engines/godot3/addons/boxmarch",
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
        import_fix="engines/unity's postprocessor sets it, or in the model import Read/Write on",
        colour_8bit=True, data_frame={"up": "+Y", "handedness": "left", "units": "metre"},
        engine_settings={"unity_model_importer": import_settings.UNITY}, helper="engines/unity/com.boxmarch.boxmarch"),
    "UNREAL": Preset(
        "UNREAL", "Unreal (FBX)", ".fbx", np.eye(3), np.array([1.0, -1.0, 1.0]),
        "FBX for Unreal's importer: left-handed Z-up centimetres (y mirrored), V flipped, box data in float UVs",
        layouts=("UV_FRAME",), length_scale=100.0, flip_v_on_import=True,
        import_settings="Static mesh import: Use Full Precision UVs on (else UVs are 16-bit halves), "
                        "Generate Lightmap UVs off (it writes into UV channel 1), Convert Scene on (default)",
        half_float_uvs=(1, 2, 3, 4, 5, 6), default_import_loss="16-bit half-float UVs",
        import_fix="import with engines/unreal/boxmarch_import.py, or Use Full Precision UVs on",
        data_frame={"up": "+Z", "handedness": "left", "units": "centimetre"},
        engine_settings={"unreal_fbx_import": import_settings.UNREAL_IMPORT,
                         "unreal_mesh_build": import_settings.UNREAL_BUILD},
        helper="engines/unreal/boxmarch_import.py"),
    "BLENDER": Preset(
        "BLENDER", "Blender (raw)", ".blend", np.eye(3), np.ones(3),
        "The selected objects in a .blend, baked data in Blender's own object space",
        data_frame=dict(_BLENDER)),
}

"""What each engine's importer must be told so the box data stay float32, as one table per
engine. Blender-free.

Each preset (formats/presets.py) names its engine's tables, which the sidecar records; the engine helpers
shipped in engines/ set the same values (engines/unity/.../BoxmarchModelPostprocessor.cs,
engines/unreal/boxmarch_import.py, the ``NAME.glb.import`` written beside a GODOT3 export), and
tests/test_engine_import_settings.py reads each helper's source and requires it to set exactly
this table; the modelled Unity and Unreal imports of the tests apply what the helpers set.
"""
from __future__ import annotations

# Godot 3.2's scene importer, [params] of NAME.glb.import: mesh compression off keeps the colour,
# normal and tangent float32 (on: 8-bit colour clamped to [0, 1], 8-bit normal and tangent).
GODOT3 = {"meshes/compress": False}

# Unity's ModelImporter, as C# assignments: Read/Write keeps TexCoord2-7 float32 under the
# Player's vertex compression; Mesh Compression quantizes UVs and colours; the NORMAL_FRAME
# frame is the file's normal and tangent, which Calculate would replace.
UNITY = {"isReadable": "true", "meshCompression": "ModelImporterMeshCompression.Off",
         "importNormals": "ModelImporterNormals.Import", "importTangents": "ModelImporterTangents.Import"}

# Unreal's FBX import (unreal.FbxStaticMeshImportData) and the static mesh's build settings
# (unreal.MeshBuildSettings of LOD 0): Convert Scene Unit is off by default (metres would stay
# metres), UVs are 16-bit halves unless Use Full Precision UVs, lightmap generation writes into
# a UV channel, recomputed normals and tangents replace the file's.
UNREAL_IMPORT = {"convert_scene": True, "convert_scene_unit": True, "generate_lightmap_u_vs": False,
                 "normal_import_method": "FBXNIM_IMPORT_NORMALS_AND_TANGENTS"}
UNREAL_BUILD = {"use_full_precision_u_vs": True, "generate_lightmap_u_vs": False, "recompute_normals": False,
                "recompute_tangents": False}


def godot3_import_path(filepath: str) -> str:
    """Godot 3's import settings of ``filepath``: ``NAME.glb.import`` beside it."""
    return filepath + ".import"


def godot3_import_text() -> str:
    """The ``.import`` file Godot 3.2 honours when it first imports the .glb beside it: the scene
    importer with GODOT3's parameters (the rest take Godot's defaults; Godot completes the file)."""
    params = "".join(f"{key}={str(value).lower()}\n" for key, value in GODOT3.items())
    return f'[remap]\n\nimporter="scene"\ntype="PackedScene"\n\n[params]\n\n{params}'


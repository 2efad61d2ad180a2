"""Imports a boxmarch UNREAL export (NAME.fbx, with its sidecar NAME.boxmarch.json beside it) into
Unreal Editor with the settings the box data need (docs/ENGINES.md), then sets the static mesh's
build settings. Run it in the editor's Python console or with its command line:

    py "PATH/engines/unreal/boxmarch_import.py" "PATH/NAME.fbx" /Game/Boxmarch

Written for Unreal 5's Python API (unreal.AssetImportTask, unreal.StaticMeshEditorSubsystem); it
has never run in Unreal: boxmarch's tests parse it and require IMPORT_DATA and BUILD_SETTINGS to
be the settings their modelled Unreal import applies (tests/test_engine_import_settings.py).
"""
import json
import os
import sys

FORMAT_VERSION = 1
PRESET = "UNREAL"
LAYOUTS_READ = ("UV_FRAME",)
SIDECAR_SUFFIX = ".boxmarch.json"

# unreal.FbxStaticMeshImportData: the file's axes and metres converted to Unreal's (Convert Scene
# Unit is off by default), no lightmap UVs written into the box channels, the file's normals and
# tangents kept.
IMPORT_DATA = {"convert_scene": True, "convert_scene_unit": True, "generate_lightmap_u_vs": False,
               "normal_import_method": "FBXNIM_IMPORT_NORMALS_AND_TANGENTS"}
# unreal.MeshBuildSettings of LOD 0: float32 UVs (the default stores 16-bit halves, about 1e-3 of
# a half-extent off), nothing recomputed or generated over the file's channels.
BUILD_SETTINGS = {"use_full_precision_u_vs": True, "generate_lightmap_u_vs": False, "recompute_normals": False,
                  "recompute_tangents": False}


def sidecar_refusal(sidecar):
    """Why this script does not import the model ``sidecar`` (a dict) describes, or None."""
    if not isinstance(sidecar, dict):
        return "the sidecar is not a boxmarch sidecar"
    if sidecar.get("format_version") != FORMAT_VERSION:
        return f"the sidecar has format version {sidecar.get('format_version')!r}; this script reads {FORMAT_VERSION}"
    if sidecar.get("preset") != PRESET:
        return f"the model was exported with the {sidecar.get('preset')} preset: export with the UNREAL preset"
    if sidecar.get("layout") not in LAYOUTS_READ:
        return f"layout {sidecar.get('layout')} is not read by the boxmarch material function ({', '.join(LAYOUTS_READ)})"
    return None


def read_sidecar(fbx_path):
    """The sidecar beside ``fbx_path`` as a dict; raises ValueError naming what is wrong."""
    path = os.path.splitext(fbx_path)[0] + SIDECAR_SUFFIX
    if not os.path.isfile(path):
        raise ValueError(f"{fbx_path}: no boxmarch sidecar {path} beside it: export it with boxmarch")
    with open(path, encoding="utf-8") as f:
        try:
            sidecar = json.load(f)
        except json.JSONDecodeError as error:
            raise ValueError(f"{path} is not JSON: {error}") from None
    refusal = sidecar_refusal(sidecar)
    if refusal:
        raise ValueError(f"{fbx_path}: {refusal}")
    return sidecar


def import_boxmarch_fbx(fbx_path, destination):
    """Imports ``fbx_path`` into the content folder ``destination`` (e.g. /Game/Boxmarch) with
    IMPORT_DATA, then applies BUILD_SETTINGS to every static mesh imported. Returns their paths."""
    import unreal

    read_sidecar(fbx_path)
    data = unreal.FbxStaticMeshImportData()
    for key, value in IMPORT_DATA.items():
        data.set_editor_property(key, getattr(unreal.FBXNormalImportMethod, value) if key == "normal_import_method"
                                 else value)
    options = unreal.FbxImportUI()
    options.set_editor_property("import_mesh", True)
    options.set_editor_property("import_as_skeletal", False)
    options.set_editor_property("import_materials", False)
    options.set_editor_property("import_textures", False)
    options.set_editor_property("static_mesh_import_data", data)
    task = unreal.AssetImportTask()
    for key, value in (("filename", fbx_path), ("destination_path", destination), ("automated", True),
                       ("replace_existing", True), ("save", True), ("options", options)):
        task.set_editor_property(key, value)
    unreal.AssetToolsHelpers.get_asset_tools().import_asset_tasks([task])
    meshes = unreal.get_editor_subsystem(unreal.StaticMeshEditorSubsystem)
    imported = []
    for path in task.get_editor_property("imported_object_paths"):
        mesh = unreal.EditorAssetLibrary.load_asset(path)
        if not isinstance(mesh, unreal.StaticMesh):
            continue
        settings = meshes.get_lod_build_settings(mesh, 0)
        for key, value in BUILD_SETTINGS.items():
            settings.set_editor_property(key, value)
        meshes.set_lod_build_settings(mesh, 0, settings)
        unreal.EditorAssetLibrary.save_loaded_asset(mesh)
        imported.append(path)
    return imported


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: boxmarch_import.py PATH/NAME.fbx /Game/Folder")
    print(import_boxmarch_fbx(sys.argv[1], sys.argv[2]))

"""Imports a boxmarch UNREAL export (NAME.fbx, with its sidecar NAME.boxmarch.json beside it) into
Unreal Editor with the settings the box data need (docs/ENGINES.md), then sets the static mesh's
build settings. Run it in the editor's Python console or with its command line:

    py "PATH/engines/unreal/boxmarch_import.py" "PATH/NAME.fbx" /Game/Boxmarch

Written for Unreal 5's Python API (unreal.AssetImportTask, unreal.StaticMeshEditorSubsystem); it
has never run in Unreal: boxmarch's tests parse it and require IMPORT_DATA and BUILD_SETTINGS to
be the settings their modelled Unreal import applies (tests/test_engine_import_settings.py).
"""
import json
import math
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


MAX_SIDECAR_BYTES = 16777216  # the limits every boxmarch helper applies before parsing (docs/FORMAT.md)
MAX_SIDECAR_DEPTH = 32
UTF8_BOM = b"\xef\xbb\xbf"


def _shown(sidecar, key):
    """The value at ``key`` as JSON, cut to 40 characters, or "missing"; a number beyond a
    double's range (1e400, valid JSON, parsed as an infinity) in words."""
    if key not in sidecar:
        return "missing"
    value = sidecar[key]
    if isinstance(value, float) and not math.isfinite(value):
        return "a number beyond the range of a double"
    text = json.dumps(value, allow_nan=False)  # finite here; ASCII: every line break in a string escaped
    return text if len(text) <= 40 else text[:40] + "..."


def _whole(value, top):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and 0 <= value <= top and value == int(value)


def sidecar_refusal(sidecar):
    """Why this script does not import the model ``sidecar`` (parsed JSON) describes, or None:
    the checks every boxmarch helper makes, in the same order (docs/FORMAT.md)."""
    if not isinstance(sidecar, dict):
        return "not a JSON object"
    version = sidecar.get("format_version")
    if isinstance(version, bool) or not isinstance(version, (int, float)) or version != FORMAT_VERSION:
        return f"format_version must be {FORMAT_VERSION} (the format this script reads), not " + _shown(sidecar, "format_version")
    if not isinstance(sidecar.get("preset"), str) or sidecar["preset"] != PRESET:
        return f'preset must be "{PRESET}", not {_shown(sidecar, "preset")}: export with the UNREAL preset'
    if not isinstance(sidecar.get("layout"), str) or sidecar["layout"] not in LAYOUTS_READ:
        return (f"layout must be one of {', '.join(LAYOUTS_READ)} (what the boxmarch material function reads), "
                f"not {_shown(sidecar, 'layout')}")
    if not isinstance(sidecar.get("skinned"), bool):
        return f"skinned must be true or false, not {_shown(sidecar, 'skinned')}"
    if not _whole(sidecar.get("box_count"), 2**31 - 1):
        return f"box_count must be a whole number from 0 to 2147483647, not {_shown(sidecar, 'box_count')}"
    return None


def _nesting(data):
    """The deepest nesting of brackets in JSON text ``data`` (bytes), strings skipped."""
    depth = deepest = 0
    in_string = escaped = False
    for byte in data:
        if in_string:
            escaped, in_string = (False, True) if escaped else (byte == 0x5C, byte != 0x22)
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_SIDECAR_DEPTH:
                break
        elif byte in (0x5D, 0x7D):
            depth -= 1
    return deepest


def _refuse_constant(token):
    raise ValueError(f"{token} is no JSON number")


def read_sidecar(fbx_path):
    """The sidecar beside ``fbx_path`` as a dict; raises ValueError, one line naming the sidecar
    and what is wrong, for anything but a sidecar this script reads."""
    path = os.path.splitext(fbx_path)[0] + SIDECAR_SUFFIX
    if not os.path.isfile(path):
        raise ValueError(f"boxmarch: {fbx_path}: no boxmarch sidecar {path} beside it: export it with boxmarch")
    with open(path, "rb") as f:
        data = f.read(MAX_SIDECAR_BYTES + 1)
    if len(data) > MAX_SIDECAR_BYTES:
        raise ValueError(f"boxmarch: {path}: larger than {MAX_SIDECAR_BYTES} bytes, not a boxmarch sidecar")
    if data.startswith(UTF8_BOM):  # no part of the JSON text: one is skipped (docs/FORMAT.md)
        data = data[len(UTF8_BOM):]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"boxmarch: {path}: not UTF-8 text (byte {error.start})") from None
    if _nesting(data) > MAX_SIDECAR_DEPTH:
        raise ValueError(f"boxmarch: {path}: brackets nested more than {MAX_SIDECAR_DEPTH} deep")
    try:
        sidecar = json.loads(text, parse_constant=_refuse_constant)
    except ValueError as error:  # json.JSONDecodeError included
        raise ValueError(f"boxmarch: {path}: not JSON ({str(error).splitlines()[0]})") from None
    refusal = sidecar_refusal(sidecar)
    if refusal:
        raise ValueError(f"boxmarch: {path}: {refusal}")
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

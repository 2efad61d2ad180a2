"""A stub of the part of Unreal 5's editor Python API (the ``unreal`` module) that
engines/unreal/boxmarch_import.py calls, so the script runs here and what it sets is recorded.
Names, property names and defaults are Unreal's (Python API reference: FbxStaticMeshImportData,
FbxImportUI, AssetImportTask, MeshBuildSettings, whose defaults are FMeshBuildSettings' in
EngineTypes.h). Modelled, and only as far as the tests need: set_editor_property refuses a
property the class does not have (as Unreal does); an import task with automated options imports
the file as one static mesh ``destination/NAME`` carrying the task's FbxStaticMeshImportData;
LOD build settings are copies (get) written back by set_lod_build_settings; a saved asset keeps
the state it was saved in. Never compared with a real Unreal."""
import copy
import enum
import os
import sys
import types
from contextlib import contextmanager


class FBXNormalImportMethod(enum.Enum):
    FBXNIM_COMPUTE_NORMALS = 0
    FBXNIM_IMPORT_NORMALS = 1
    FBXNIM_IMPORT_NORMALS_AND_TANGENTS = 2


class _Properties:
    """Editor properties: DEFAULTS holds every property the class has, with Unreal's default."""
    DEFAULTS: dict = {}

    def __init__(self):
        self._values = dict(self.DEFAULTS)

    def set_editor_property(self, name, value):
        if name not in self._values:
            raise Exception(f"{type(self).__name__}: Failed to find property '{name}'")
        self._values[name] = value

    def get_editor_property(self, name):
        if name not in self._values:
            raise Exception(f"{type(self).__name__}: Failed to find property '{name}'")
        return self._values[name]

    def properties(self) -> dict:
        return dict(self._values)


class FbxStaticMeshImportData(_Properties):
    # FbxAssetImportData, FbxMeshImportData and FbxStaticMeshImportData's own (a subset).
    DEFAULTS = {"convert_scene": True, "convert_scene_unit": False, "force_front_x_axis": False,
                "import_uniform_scale": 1.0, "normal_import_method": FBXNormalImportMethod.FBXNIM_IMPORT_NORMALS,
                "compute_weighted_normals": False, "generate_lightmap_u_vs": True, "auto_generate_collision": True,
                "combine_meshes": False, "remove_degenerates": True, "build_nanite": False,
                "build_reversed_index_buffer": True, "one_convex_hull_per_ucx": True,
                "import_mesh_lods": False, "transform_vertex_to_absolute": True, "bake_pivot_in_vertex": False}


class FbxImportUI(_Properties):
    DEFAULTS = {"import_mesh": True, "import_as_skeletal": False, "import_materials": True, "import_textures": True,
                "import_animations": True, "automated_import_should_detect_type": True,
                "static_mesh_import_data": None, "skeletal_mesh_import_data": None}


class AssetImportTask(_Properties):
    DEFAULTS = {"filename": "", "destination_path": "", "destination_name": "", "automated": False,
                "replace_existing": False, "replace_existing_settings": False, "save": False, "options": None,
                "factory": None, "imported_object_paths": [], "async_": False}


class MeshBuildSettings(_Properties):
    DEFAULTS = {"use_mikk_t_space": True, "recompute_normals": True, "recompute_tangents": True,
                "compute_weighted_normals": False, "remove_degenerates": True, "build_reversed_index_buffer": True,
                "use_high_precision_tangent_basis": False, "use_full_precision_u_vs": False,
                "use_backwards_compatible_f16_trunc_u_vs": False, "generate_lightmap_u_vs": True,
                "generate_distance_field_as_if_two_sided": False, "support_face_remap": False,
                "min_lightmap_resolution": 64, "src_lightmap_index": 0, "dst_lightmap_index": 1,
                "distance_field_resolution_scale": 1.0, "max_lumen_mesh_cards": 12}


class StaticMesh:
    def __init__(self, path, import_data):
        self.path = path
        self.import_data = import_data.properties()
        self.lod_build_settings = {0: MeshBuildSettings()}


class StaticMeshEditorSubsystem:
    def get_lod_build_settings(self, mesh, lod):
        return copy.deepcopy(mesh.lod_build_settings[lod])

    def set_lod_build_settings(self, mesh, lod, settings):
        mesh.lod_build_settings[lod] = copy.deepcopy(settings)


class Unreal:
    """One editor session: the stub module's state, and what was imported and saved."""

    def __init__(self):
        self.assets = {}   # path -> StaticMesh
        self.saved = {}    # path -> (import data, LOD 0 build settings) when saved
        self.tasks = []

    def import_asset_tasks(self, tasks):
        for task in tasks:
            self.tasks.append(task)
            options = task.get_editor_property("options")
            if not task.get_editor_property("automated") or options is None:
                continue  # Unreal would show its import dialog: nothing imported unattended
            data = options.get_editor_property("static_mesh_import_data") or FbxStaticMeshImportData()
            if options.get_editor_property("import_as_skeletal") or not options.get_editor_property("import_mesh"):
                continue
            name = os.path.splitext(os.path.basename(task.get_editor_property("filename")))[0]
            path = f"{task.get_editor_property('destination_path').rstrip('/')}/{name}.{name}"
            self.assets[path] = StaticMesh(path, data)
            task.set_editor_property("imported_object_paths", [path])
            if task.get_editor_property("save"):
                self.save(self.assets[path])

    def save(self, asset, only_if_is_dirty=True):
        self.saved[asset.path] = (dict(asset.import_data), asset.lod_build_settings[0].properties())
        return True

    def module(self) -> types.ModuleType:
        unreal = types.ModuleType("unreal")
        unreal.FBXNormalImportMethod = FBXNormalImportMethod
        unreal.FbxStaticMeshImportData, unreal.FbxImportUI = FbxStaticMeshImportData, FbxImportUI
        unreal.AssetImportTask, unreal.MeshBuildSettings, unreal.StaticMesh = AssetImportTask, MeshBuildSettings, StaticMesh
        unreal.StaticMeshEditorSubsystem = StaticMeshEditorSubsystem
        tools = types.SimpleNamespace(import_asset_tasks=self.import_asset_tasks)
        unreal.AssetToolsHelpers = types.SimpleNamespace(get_asset_tools=lambda: tools)
        subsystems = {StaticMeshEditorSubsystem: StaticMeshEditorSubsystem()}
        unreal.get_editor_subsystem = lambda kind: subsystems[kind]
        unreal.EditorAssetLibrary = types.SimpleNamespace(load_asset=self.assets.get, save_loaded_asset=self.save)
        return unreal


@contextmanager
def unreal_session():
    """An Unreal session whose stub module is ``import unreal`` meanwhile."""
    session = Unreal()
    saved = sys.modules.get("unreal")
    sys.modules["unreal"] = session.module()
    try:
        yield session
    finally:
        if saved is None:
            sys.modules.pop("unreal", None)
        else:
            sys.modules["unreal"] = saved

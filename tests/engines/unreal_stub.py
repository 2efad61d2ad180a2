"""A stub of the part of Unreal 5's editor Python API (the ``unreal`` module) that
engines/unreal/boxmarch_import.py calls, so the script runs here and what it sets is recorded.
Names, property names and defaults are Unreal's (Python API reference: FbxStaticMeshImportData,
FbxImportUI, AssetImportTask, MeshBuildSettings, whose defaults are FMeshBuildSettings' in
EngineTypes.h; for engines/unreal/boxmarch_decode_vectors.py: StaticMeshDescription, VertexInstanceID,
Transform.transform_location, SystemLibrary.draw_debug_line, EditorActorSubsystem,
UnrealEditorSubsystem). Modelled, and only as far as the tests need: set_editor_property refuses a
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


class _Struct:
    """A struct of named float fields, built positionally or by name (unreal.Vector(x, y, z))."""
    FIELDS: tuple = ()

    def __init__(self, *values, **named):
        for name, value in zip(self.FIELDS, values):
            setattr(self, name, float(value))
        for name in self.FIELDS[len(values):]:
            setattr(self, name, float(named.pop(name, 0.0)))
        if named:
            raise TypeError(f"{type(self).__name__}: no field {', '.join(named)}")


class Vector(_Struct):
    FIELDS = ("x", "y", "z")


class Vector2D(_Struct):
    FIELDS = ("x", "y")


class LinearColor(_Struct):
    FIELDS = ("r", "g", "b", "a")


class VertexInstanceID:
    def __init__(self, id_value=0):
        self.id_value = int(id_value)


class VertexID(VertexInstanceID):
    pass


class Transform:
    """A local-to-world transform as a 4x4 matrix (column vectors)."""

    def __init__(self, matrix=None):
        self.matrix = [[float(i == j) for j in range(4)] for i in range(4)] if matrix is None else matrix

    def transform_location(self, v):
        m = self.matrix
        return Vector(*(m[i][0] * v.x + m[i][1] * v.y + m[i][2] * v.z + m[i][3] for i in range(3)))


class StaticMeshDescription:
    """LOD 0 of an imported mesh: one vertex per vertex instance, ``positions`` (n, 3) and ``uvs``
    (UV channel -> (n, 2)), as the modelled import stores them."""

    def __init__(self, positions, uvs):
        self.positions, self.uvs = positions, uvs

    def get_vertex_instance_count(self):
        return len(self.positions)

    def get_vertex_instance_vertex(self, vertex_instance_id):
        return VertexID(vertex_instance_id.id_value)

    def get_vertex_position(self, vertex_id):
        return Vector(*self.positions[vertex_id.id_value])

    def get_vertex_instance_uv(self, vertex_instance_id, uv_index=0):
        return Vector2D(*self.uvs[uv_index][vertex_instance_id.id_value])


class ImportedStaticMesh:
    """A static mesh asset whose mesh description the tests give."""

    def __init__(self, description):
        self.description = description

    def get_static_mesh_description(self, lod_index):
        if lod_index != 0:
            raise Exception(f"StaticMesh: no LOD {lod_index}")
        return self.description


class StaticMeshComponent(_Properties):
    DEFAULTS = {"static_mesh": None}

    def __init__(self, static_mesh=None, transform=None):
        super().__init__()
        self.set_editor_property("static_mesh", static_mesh)
        self.transform = transform or Transform()

    def get_world_transform(self):
        return self.transform


class Actor:
    def __init__(self, label, component=None):
        self.label, self.component = label, component

    def get_actor_label(self):
        return self.label

    def get_component_by_class(self, component_class):
        return self.component if isinstance(self.component, component_class) else None


class Unreal:
    """One editor session: the stub module's state, and what was imported and saved; the actors
    selected in the level, the debug lines drawn ((start, end, colour, duration) as tuples) and
    the messages logged."""

    def __init__(self):
        self.assets = {}   # path -> StaticMesh
        self.saved = {}    # path -> (import data, LOD 0 build settings) when saved
        self.tasks = []
        self.selected = []
        self.lines = []
        self.log = []

    def draw_debug_line(self, world_context_object, line_start, line_end, line_color=None, duration=0.0,
                        thickness=0.0):
        if world_context_object is not self:
            raise Exception("SystemLibrary.draw_debug_line: no world context")
        colour = line_color or LinearColor()
        self.lines.append(((line_start.x, line_start.y, line_start.z), (line_end.x, line_end.y, line_end.z),
                           (colour.r, colour.g, colour.b, colour.a), duration))

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
        unreal.Vector, unreal.Vector2D, unreal.LinearColor, unreal.Transform = Vector, Vector2D, LinearColor, Transform
        unreal.VertexInstanceID, unreal.VertexID, unreal.StaticMeshComponent = VertexInstanceID, VertexID, StaticMeshComponent
        unreal.SystemLibrary = types.SimpleNamespace(draw_debug_line=self.draw_debug_line)
        unreal.UnrealEditorSubsystem = type("UnrealEditorSubsystem", (), {"get_editor_world": lambda _s: self})
        unreal.EditorActorSubsystem = type("EditorActorSubsystem", (), {"get_selected_level_actors": lambda _s: list(self.selected)})
        unreal.log_warning = lambda text: self.log.append(("warning", text))
        unreal.log_error = lambda text: self.log.append(("error", text))
        subsystems = {StaticMeshEditorSubsystem: StaticMeshEditorSubsystem(),
                      unreal.UnrealEditorSubsystem: unreal.UnrealEditorSubsystem(),
                      unreal.EditorActorSubsystem: unreal.EditorActorSubsystem()}
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

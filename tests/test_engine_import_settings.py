"""The engine-side helpers in engines/ against the one table of import settings
(addon/boxmarch/formats/import_settings.py, which the sidecar records) and the sidecar's values.

Unity: the AssetPostprocessor is compiled with mono's mcs against a stub of the Unity API it calls
and run under mono, its OnPreprocessModel invoked by name as Unity sends it, on a boxmarch export,
a foreign model and refused sidecars; the stub's ModelImporter records what is set
(tests/engines/unity_stub). Never run in Unity; a misspelled Unity member must fail the compile.
Unreal: the import script is run against a stub ``unreal`` module that records what it sets
(tests/engines/unreal_stub.py), never in Unreal; the Custom node code is compiled as HLSL by
glslangValidator. The modelled imports of tests/engine_scene.py are built from what the helpers
set when run, so the decode tests of the models test what the helpers do."""

import re

import numpy as np
import pytest

from tests.engine_scene import UNITY, UNREAL, NotModelled, unity_import, unreal_import
from tests.engines import import_helpers
from tests.helpers.glsl import compile_hlsl_fragment


@pytest.mark.slow  # compiles and runs C# under mono
def test_unity_postprocessor_constants_are_the_sidecar_values():
    """The compiled assembly's constants, read by reflection."""
    from boxmarch.formats import sidecar, presets

    constants = import_helpers.unity_constants()
    assert constants == {"FormatVersion": sidecar.FORMAT_VERSION, "Preset": "UNITY",
                         "SidecarSuffix": sidecar.SIDECAR_SUFFIX, "LayoutsRead": constants["LayoutsRead"]}
    assert sorted(constants["LayoutsRead"]) == sorted(presets.PRESETS["UNITY"].layouts)


@pytest.mark.slow  # compiles and runs C# under mono
def test_unity_postprocessor_run_as_unity_calls_it_sets_the_table_and_refuses_bad_sidecars():
    """The postprocessor compiled and run under mono, OnPreprocessModel invoked by name as Unity
    sends it (tests/engines/unity_stub/UnityImportHarness.cs): a boxmarch UNITY export in each
    layout gets exactly the table; a model without a sidecar nothing and no message; a sidecar
    that is not JSON, not an object, empty, of version 2, of another preset or of a layout the
    package does not read: nothing set and one error naming the sidecar."""
    from boxmarch.formats import import_settings

    run = import_helpers.unity_import_run()
    assert import_helpers.unity_import_faults(run, import_settings.UNITY) == []
    assert import_helpers.unity_settings() == import_settings.UNITY


# One-line changes of the package's Editor sources that its run must catch: each compiles, and
# each leaves a case of the run wrong (what Unity would do with it).
UNITY_MUTATIONS = {
    "importer == null inverted: no setting ever applied": (r"importer\s*==\s*null", "importer != null"),
    "preset check inverted: UNITY refused, other presets set": (r"!=(\s*)([Pp]reset)\b", r"==\1\2"),
    "OnPreprocessModel misspelled: Unity never calls it": (r"\bOnPreprocessModel\b", "OnPreProcessModel"),
    "refusal not returned: a bad sidecar's model is set": (r"(LogError\([^;]*;)\s*return;", r"\1"),
}


@pytest.mark.slow
@pytest.mark.parametrize("mutation", sorted(UNITY_MUTATIONS))
def test_unity_postprocessor_run_catches_each_mutation(mutation):
    from boxmarch.formats import import_settings

    pattern, replacement = UNITY_MUTATIONS[mutation]
    mutated, count = {}, 0
    for name, text in import_helpers.unity_editor_sources().items():
        mutated[name], found = re.subn(pattern, replacement, text, count=1)
        count += found
    assert count == 1, f"{mutation}: the pattern is in {count} places of the Editor sources, not one"
    assert import_helpers.unity_import_faults(import_helpers.unity_import_run(mutated), import_settings.UNITY) != []


@pytest.mark.slow
def test_unity_postprocessor_compiles_against_the_stub_and_a_misspelled_member_does_not(tmp_path):
    import_helpers.need_mono()
    source = import_helpers.UNITY_POSTPROCESSOR.read_text()
    built = import_helpers.compile_unity(source, tmp_path)
    assert built.returncode == 0, built.stdout + built.stderr
    assert (tmp_path / "boxmarch.dll").stat().st_size > 0
    for right, wrong in (("importer.isReadable", "importer.isReadible"), ("ModelImporterNormals.Import",
                                                                         "ModelImporterNormals.Imported")):
        assert right in source
        failed = import_helpers.compile_unity(source.replace(right, wrong), tmp_path)
        assert failed.returncode != 0 and "error CS" in failed.stdout + failed.stderr, failed.stdout


def test_unity_package_ships_the_hlsl_as_generated():
    """The UPM package's Runtime/Shaders are shaders/generate.py's copies of shaders/hlsl (its
    --check, run by tests/test_engine_shaders.py, fails on any drift); here: every file a
    material includes is in the package."""
    shaders = import_helpers.UNITY_PACKAGE / "Runtime" / "Shaders"
    names = {p.name for p in shaders.iterdir()}
    for path in shaders.iterdir():
        for line in path.read_text().splitlines():
            if line.strip().startswith("#include") and "Unity" not in line:
                assert line.split('"')[1] in names, (path.name, line)
    assert (import_helpers.UNITY_PACKAGE / "package.json").is_file()


def test_unreal_script_parses_and_sets_the_table():
    from boxmarch.formats import import_settings, sidecar, presets

    constants = import_helpers.unreal_constants()  # ast.parse of the whole script
    assert constants["IMPORT_DATA"] == import_settings.UNREAL_IMPORT
    assert constants["BUILD_SETTINGS"] == import_settings.UNREAL_BUILD
    assert constants["FORMAT_VERSION"] == sidecar.FORMAT_VERSION and constants["PRESET"] == "UNREAL"
    assert constants["SIDECAR_SUFFIX"] == sidecar.SIDECAR_SUFFIX
    assert constants["LAYOUTS_READ"] == presets.PRESETS["UNREAL"].layouts


def test_unreal_script_refuses_sidecars_it_does_not_read():
    """The script's sidecar check is plain Python: run here without Unreal."""
    namespace = {"__name__": "boxmarch_import"}
    exec(compile(import_helpers.UNREAL_SCRIPT.read_text(), str(import_helpers.UNREAL_SCRIPT), "exec"), namespace)
    refusal = namespace["sidecar_refusal"]
    good = {"format_version": 1, "preset": "UNREAL", "layout": "UV_FRAME", "skinned": False, "box_count": 3}
    assert refusal(good) is None
    assert "UNREAL preset" in refusal(dict(good, preset="UNITY"))
    assert "NORMAL_FRAME" in refusal(dict(good, layout="NORMAL_FRAME"))
    assert "format_version must be 1 (the format this script reads), not 2" in refusal(dict(good, format_version=2))


# What docs/ENGINES.md's Unreal row says Unreal must be told, phrase by phrase, in the part naming
# its class: "import" (FbxStaticMeshImportData) or "build" (MeshBuildSettings of LOD 0), as
# {property: value}.
UNREAL_DOCUMENTED = {
    "import": {"Convert Scene": {"convert_scene": True}, "Convert Scene Unit": {"convert_scene_unit": True},
               "no lightmap UVs": {"generate_lightmap_u_vs": False},
               "Import Normals and Tangents": {"normal_import_method": "FBXNIM_IMPORT_NORMALS_AND_TANGENTS"}},
    "build": {"Use Full Precision UVs": {"use_full_precision_u_vs": True},
              "no recomputed normals or tangents": {"recompute_normals": False, "recompute_tangents": False},
              "no lightmap UVs": {"generate_lightmap_u_vs": False}},
}


def unreal_faults(saved) -> list:
    """How the (import data, build settings) the script saved differ from the documented ones."""
    found = dict(zip(("import", "build"), saved))
    return [f"{phrase}: {part}.{key} = {found[part].get(key)!r}, not {value!r}"
            for part, phrases in UNREAL_DOCUMENTED.items() for phrase, named in phrases.items()
            for key, value in named.items() if found[part].get(key) != value]


def test_unreal_script_run_against_the_stub_saves_what_the_docs_say_unreal_needs():
    """import_boxmarch_fbx run against the stub ``unreal`` module: the one static mesh it imports
    is saved with every setting docs/ENGINES.md names (Unreal's defaults differ in each: the
    stub starts from them), which is the table the sidecar records."""
    from boxmarch.formats import import_settings

    row = next(line for line in (import_helpers.REPO / "docs" / "ENGINES.md").read_text().splitlines()
               if line.startswith("| Unreal | "))
    import_part, build_part = row.split(" | ")[1].split("(`FbxStaticMeshImportData`)")
    assert "(`MeshBuildSettings` of LOD 0)" in build_part
    for part, text in (("import", import_part), ("build", build_part)):
        assert sorted(p.strip() for p in re.split(r"[,;]", text.split("(`")[0]) if p.strip()) == sorted(
            UNREAL_DOCUMENTED[part]), text
    saved = import_helpers.unreal_settings()
    assert unreal_faults(saved) == []
    assert {k: saved[0][k] for k in import_settings.UNREAL_IMPORT} == import_settings.UNREAL_IMPORT
    assert {k: saved[1][k] for k in import_settings.UNREAL_BUILD} == import_settings.UNREAL_BUILD


def test_unreal_script_run_imports_nothing_for_a_refused_sidecar():
    from boxmarch.formats import sidecar

    for changes in ({"preset": "UNITY"}, {"layout": "NORMAL_FRAME"}, {"format_version": sidecar.FORMAT_VERSION + 1}):
        session, result = import_helpers.unreal_import_run(sidecar=import_helpers.unreal_sidecar(**changes))
        # one line naming the model or its sidecar
        assert isinstance(result, ValueError) and re.search(r"model\.(fbx|boxmarch\.json)", str(result)), (changes, result)
        assert session.tasks == [] and session.saved == {}


# One-line changes of the script that its run must catch.
UNREAL_MUTATIONS = {
    "build-settings loop emptied": (r"(for key, value in BUILD_SETTINGS\.items\(\):\n\s*)settings\.set_editor_property\(key, value\)",
                                    r"\1pass"),
    "build settings not written back": (r"meshes\.set_lod_build_settings\(mesh, 0, settings\)", "pass"),
    "import-data loop emptied": (r"(for key, value in IMPORT_DATA\.items\(\):\n\s*)data\.set_editor_property\(",
                                 r"\1(lambda *a: None)("),
    "import data not handed to the options": (r'options\.set_editor_property\("static_mesh_import_data", data\)',
                                              "pass"),
    "mesh not saved after its build settings": (r"unreal\.EditorAssetLibrary\.save_loaded_asset\(mesh\)", "pass"),
}


@pytest.mark.parametrize("mutation", sorted(UNREAL_MUTATIONS))
def test_unreal_script_run_catches_each_mutation(mutation):
    pattern, replacement = UNREAL_MUTATIONS[mutation]
    mutated, count = re.subn(pattern, replacement, import_helpers.UNREAL_SCRIPT.read_text())
    assert count == 1, f"{mutation}: the pattern is no longer in the script"
    session, result = import_helpers.unreal_import_run(mutated)
    saved = list(session.saved.values())
    assert not isinstance(result, Exception), result
    assert len(saved) != 1 or unreal_faults(saved[0]) != [], mutation


def test_unreal_material_function_compiles_as_hlsl(tmp_path):
    body = import_helpers.UNREAL_MATERIAL.read_text()
    inputs = ", ".join(f"float2 {n}" for n in ("QuatXY", "QuatZW", "OffsetXY", "OffsetZIndex", "HalfXY", "HalfZ"))
    # The function Unreal wraps a Custom node in: its inputs as parameters, additional outputs as out.
    wrapper = (f"float3 boxmarch_uv_frame({inputs}, out float3 HalfExtents, out float BoxIndex)\n{{\n{body}\n}}\n"
               "float4 main(float2 a : TEXCOORD1, float2 b : TEXCOORD2, float2 c : TEXCOORD3, float2 d : TEXCOORD4,"
               " float2 e : TEXCOORD5, float2 g : TEXCOORD6) : SV_Target\n{\n  float3 h; float i;\n"
               "  return float4(boxmarch_uv_frame(a, b, c, d, e, g, h, i) + h, i);\n}\n")
    for name, text, ok in (("good.hlsl", wrapper, True), ("bad.hlsl", wrapper.replace("q.w", "q.v"), False)):
        proc = compile_hlsl_fragment(tmp_path, name, text)
        assert (proc.returncode == 0) == ok, proc.stdout + proc.stderr


def unreal_depth_offset_expression() -> str:
    """The expression BoxmarchDepthOffset.ush returns (its one statement, after the comments)."""
    code = [line for line in import_helpers.UNREAL_DEPTH_OFFSET.read_text().splitlines()
            if line.strip() and not line.lstrip().startswith("//")]
    assert len(code) == 1 and code[0].startswith("return ") and code[0].endswith(";"), code
    return code[0][len("return "):-1]


def test_unreal_depth_offset_compiles_as_hlsl(tmp_path):
    """The Custom node as Unreal wraps it (inputs as parameters); a misspelled input must fail."""
    body = import_helpers.UNREAL_DEPTH_OFFSET.read_text()
    wrapper = ("float boxmarch_depth_offset(float3 HitWorld, float3 PixelWorld, float3 ViewForward)\n{\n"
               f"{body}\n}}\n"
               "float4 main(float3 a : TEXCOORD0, float3 b : TEXCOORD1, float3 c : TEXCOORD2) : SV_Target\n{\n"
               "  return float4(boxmarch_depth_offset(a, b, c), 0.0, 0.0, 1.0);\n}\n")
    for name, text, ok in (("good.hlsl", wrapper, True), ("bad.hlsl", wrapper.replace("ViewForward), 0.0)", "ViewFwd), 0.0)"), False)):
        proc = compile_hlsl_fragment(tmp_path, name, text)
        assert (proc.returncode == 0) == ok, proc.stdout + proc.stderr


def reversed_z_depth_error(offset_expression: str, seed: int = 0) -> tuple:
    """Rays from a perspective camera through a sphere inside a turned box: Unreal's depth of a
    fragment whose Pixel Depth Offset is ``offset_expression`` (HLSL's dot and max, evaluated
    over the rays), against the device depth of the analytic ray-sphere hit. Unreal adds the
    offset to the pixel's view-space depth w (clip w) and, reversed Z with an infinite far plane,
    stores near / w. Returns (worst relative depth error, whether every stored depth is at most
    the rasterised face's: SV_DepthLessEqual)."""
    rng = np.random.default_rng(seed)
    near = 10.0  # cm, Unreal's default near clip plane
    turn, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    forward = turn[:, 2]
    camera = rng.normal(size=3) * 100.0
    centre, radius = camera + forward * 800.0 + turn[:, 0] * 150.0, 120.0
    box_axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    half = np.array([1.3, 1.1, 1.6]) * radius
    # rays towards points inside the sphere: every one of them hits it
    inside = rng.normal(size=(4000, 3))
    inside *= radius * rng.uniform(0.0, 0.95, size=(4000, 1)) / np.linalg.norm(inside, axis=1, keepdims=True)
    targets = centre + inside
    d = targets - camera
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    oc = camera - centre
    b = d @ oc
    t_hit = -b - np.sqrt(b * b - (oc @ oc - radius * radius))
    # the face the ray enters the box through (slab test in the box's axes)
    o_local, d_local = oc @ box_axes, d @ box_axes
    t_face = np.max(np.minimum((-half - o_local) / d_local, (half - o_local) / d_local), axis=1)
    assert np.all(t_face < t_hit) and np.all(t_face > near)
    scope = {"HitWorld": camera + d * t_hit[:, None], "PixelWorld": camera + d * t_face[:, None],
             "ViewForward": forward, "dot": lambda a, c: np.sum(a * c, axis=-1), "max": np.maximum}
    offset = eval(offset_expression, {"__builtins__": {}}, scope)  # noqa: S307 (the shipped expression)
    pixel_w = (scope["PixelWorld"] - camera) @ forward
    stored = near / (pixel_w + offset)
    truth = near / ((scope["HitWorld"] - camera) @ forward)
    return float(np.max(np.abs(stored - truth) / truth)), bool(np.all(stored <= near / pixel_w))


def test_unreal_depth_offset_gives_the_hit_depth():
    error, conservative = reversed_z_depth_error(unreal_depth_offset_expression())
    assert error < 1e-12 and conservative
    # Negative control: the distance along the ray, the obvious wrong offset, misses off-centre.
    wrong_error, _ = reversed_z_depth_error("max(dot(HitWorld - PixelWorld, (HitWorld - PixelWorld)"
                                            " / dot(HitWorld - PixelWorld, HitWorld - PixelWorld)[..., None] ** 0.5),"
                                            " 0.0)")
    assert wrong_error > 1e-4, wrong_error


def test_godot3_plugin_and_import_file_set_the_table():
    from boxmarch.formats import import_settings, sidecar, presets

    constants = import_helpers.godot3_constants()
    assert constants["PARAMS"] == import_settings.GODOT3
    assert constants["FORMAT_VERSION"] == sidecar.FORMAT_VERSION and constants["PRESET"] == "GODOT3"
    assert constants["SIDECAR_SUFFIX"] == sidecar.SIDECAR_SUFFIX
    assert tuple(constants["LAYOUTS_READ"]) == presets.PRESETS["GODOT3"].layouts
    assert "meshes/compress=false\n" in import_settings.godot3_import_text()


def same_model(a, b):
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


@pytest.mark.slow  # compiles and runs C# under mono
def test_modelled_imports_follow_the_helpers_settings():
    """The models used by the decode tests are those of the helpers' settings; changing one
    setting changes the model (or is refused as not modelled)."""
    from boxmarch.formats import import_settings

    assert same_model(UNITY, unity_import(import_settings.UNITY)) and UNITY["half_float_channels"] == ()
    assert UNITY["file_frame"] is True
    assert unity_import(dict(import_settings.UNITY, isReadable="false"))["half_float_channels"] == (2, 3, 4, 5, 6)
    assert unity_import(dict(import_settings.UNITY, importTangents="ModelImporterTangents.CalculateMikk"))[
        "file_frame"] is False
    with pytest.raises(NotModelled):
        unity_import(dict(import_settings.UNITY, meshCompression="ModelImporterMeshCompression.Low"))
    assert same_model(UNREAL, unreal_import(import_settings.UNREAL_IMPORT, import_settings.UNREAL_BUILD))
    assert UNREAL["half_float_channels"] == ()
    no_full_precision = dict(import_settings.UNREAL_BUILD, use_full_precision_u_vs=False)
    assert unreal_import(import_settings.UNREAL_IMPORT, no_full_precision)["half_float_channels"] == (1, 2, 3, 4, 5, 6)
    with pytest.raises(NotModelled):
        unreal_import(dict(import_settings.UNREAL_IMPORT, convert_scene_unit=False), import_settings.UNREAL_BUILD)

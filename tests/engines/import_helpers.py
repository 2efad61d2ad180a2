"""The engine-side import helpers shipped in engines/, read as source: the settings each one sets
and the sidecar values it accepts. The modelled Unity and Unreal imports (tests/engine_scene.py)
are built from what these return, so a test of the model tests what the helper sets.
Blender-free; the Unity script is compiled with mono's mcs against tests/engines/unity_stub."""
import ast
import atexit
import functools
import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
UNITY_PACKAGE = REPO / "engines" / "unity" / "com.boxmarch.boxmarch"
UNITY_POSTPROCESSOR = UNITY_PACKAGE / "Editor" / "BoxmarchModelPostprocessor.cs"
UNITY_STUB = Path(__file__).resolve().parent / "unity_stub" / "UnityApiStub.cs"
UNITY_HARNESS = UNITY_STUB.parent / "UnityImportHarness.cs"
UNREAL_SCRIPT = REPO / "engines" / "unreal" / "boxmarch_import.py"
UNREAL_MATERIAL = REPO / "engines" / "unreal" / "BoxmarchUVFrame.ush"
UNREAL_DEPTH_OFFSET = REPO / "engines" / "unreal" / "BoxmarchDepthOffset.ush"
GODOT3_ADDON = REPO / "engines" / "godot3" / "addons" / "boxmarch"


def need_mono():
    """Fails the test (never skips) when mcs or mono is missing (scripts/setup.sh installs both)."""
    from tests.helpers.tools import need

    need(None if shutil.which("mcs") and shutil.which("mono") else "mcs or mono is missing (apt-get install mono-mcs)")


def unity_editor_sources() -> dict:
    """{file name: text} of the package's Editor sources as shipped."""
    return {path.name: path.read_text() for path in sorted(UNITY_POSTPROCESSOR.parent.glob("*.cs"))}


def compile_unity(source: str, out_dir, extra=(), target="library", others=None) -> subprocess.CompletedProcess:
    """mcs run on the stub of Unity's API, the package's other Editor sources (``others``:
    {file name: text} in their place), ``source`` (a postprocessor's text) and ``extra`` source
    paths, warnings as errors, into one assembly ``out_dir``/boxmarch.dll (or .exe for
    ``target`` "exe")."""
    need_mono()
    texts = dict(unity_editor_sources() if others is None else others, **{UNITY_POSTPROCESSOR.name: source})
    paths = []
    for name, text in texts.items():
        paths.append(Path(out_dir) / name)
        paths[-1].write_text(text)
    out = Path(out_dir) / f"boxmarch.{'dll' if target == 'library' else 'exe'}"
    return subprocess.run(["mcs", f"-target:{target}", "-warnaserror+", f"-out:{out}", str(UNITY_STUB),
                           *map(str, paths), *map(str, extra)], capture_output=True, text=True, timeout=120)


def _run_harness(harness: Path, project: Path, args) -> list:
    ran = subprocess.run(["mono", str(harness), *args], cwd=project, capture_output=True, text=True, timeout=120)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    return [line.split("\t") for line in ran.stdout.splitlines()]


def run_unity_import(harness: Path, project: Path, assets) -> dict:
    """{asset: {"set": [(property, C# value)] in the order set, "logged": [message]}} of the
    package's postprocessors run by ``harness`` (:func:`unity_harness`) on each project-relative
    asset path of ``project`` (tests/engines/unity_stub/UnityImportHarness.cs)."""
    out = {}
    for asset, _set, assigned, _logged, logged in _run_harness(harness, project, assets):
        out[asset] = {"set": [tuple(pair.split("=", 1)) for pair in assigned.split(";") if pair],
                      "logged": [message for message in logged.split("|") if message]}
    return out


def unity_constants() -> dict:
    """The postprocessor's public constants and static readonly fields (FormatVersion, Preset,
    SidecarSuffix, LayoutsRead) as the compiled assembly holds them, read by reflection."""
    harness = unity_harness()
    lines = _run_harness(harness, harness.parent, ["--constants"])
    return {name: tuple(v) if isinstance(v := json.loads(value), list) else v for name, value in lines}


def unity_harness(sources: dict | None = None) -> Path:
    """boxmarch.exe: the package's Editor ``sources`` ({file name: text}; None: as shipped), the
    stub and the import harness (AssertionError when they do not compile)."""
    return _unity_harness(tuple(sorted((unity_editor_sources() if sources is None else sources).items())))


@functools.lru_cache(maxsize=None)
def _unity_harness(sources: tuple) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="boxmarch-unity-"))
    atexit.register(shutil.rmtree, folder, True)
    texts = dict(sources)
    built = compile_unity(texts.pop(UNITY_POSTPROCESSOR.name), folder, [UNITY_HARNESS], target="exe", others=texts)
    assert built.returncode == 0, built.stdout + built.stderr
    return folder / "boxmarch.exe"


# The sidecars of the import cases: a boxmarch UNITY export's (written by formats/sidecar.py) and
# bad ones, each with what the postprocessor must do.
def unity_sidecar(layout: str) -> dict:
    from boxmarch.formats import presets, sidecar

    stats = [{"mesh": "Mixed", "vertices": 72, "boxes": 9, "transform_error": 0.0}]
    return sidecar.describe(presets.PRESETS["UNITY"], layout, "Assets/model.fbx", stats, {}, {})


def unity_import_cases() -> dict:
    """{asset name: sidecar text or None (no sidecar: a foreign model)}: a boxmarch UNITY export
    in every layout of the preset, a foreign model, and sidecars the package must refuse."""
    from boxmarch.formats import presets

    good = unity_sidecar(presets.PRESETS["UNITY"].layouts[0])
    cases = {f"boxmarch_{layout.lower()}": json.dumps(unity_sidecar(layout)) for layout in presets.PRESETS["UNITY"].layouts}
    cases.update({
        "foreign": None,
        "refused_not_json": "{\"format_version\": 1, \"preset\": \"UNITY\",",
        "refused_not_an_object": "[1, 2]",
        "refused_empty_object": "{}",
        "refused_version_2": json.dumps(dict(good, format_version=2)),
        "refused_unreal_preset": json.dumps(dict(good, preset="UNREAL")),
        "refused_gltf_preset": json.dumps(dict(good, preset="GLTF")),
        "refused_layout_normal_color": json.dumps(dict(good, layout="NORMAL_COLOR")),
    })
    return cases


def unity_import_run(sources=None) -> dict:
    """The harness's run (:func:`run_unity_import`) of the package's Editor ``sources`` ({file
    name: text}; None: as shipped) on :func:`unity_import_cases`, each model Assets/NAME.fbx with
    its sidecar beside it. Raises AssertionError when the sources do not compile."""
    harness = unity_harness(sources)
    project = Path(tempfile.mkdtemp(prefix="boxmarch-unity-project-"))
    (project / "Assets").mkdir()
    for name, text in unity_import_cases().items():
        (project / "Assets" / f"{name}.fbx").write_bytes(b"")
        if text is not None:
            (project / "Assets" / f"{name}.boxmarch.json").write_text(text)
    ran = run_unity_import(harness, project, [f"Assets/{name}.fbx" for name in unity_import_cases()])
    shutil.rmtree(project)
    return {asset[len("Assets/"):-len(".fbx")]: result for asset, result in ran.items()}


def unity_import_faults(run: dict, table: dict) -> list:
    """What a run of :func:`unity_import_run` does against the package's contract: every boxmarch
    model gets exactly ``table`` (each property once) and no message; a foreign model neither;
    every refused sidecar nothing set and one error naming the sidecar."""
    faults = []
    for name, result in run.items():
        if name.startswith("boxmarch_") and (sorted(result["set"]) != sorted(table.items()) or result["logged"]):
            faults.append(f"{name}: set {result['set']}, logged {result['logged']}")
        if name == "foreign" and (result["set"] or result["logged"]):
            faults.append(f"{name}: set {result['set']}, logged {result['logged']}")
        if name.startswith("refused_"):
            errors = [m for m in result["logged"] if m.startswith("error: ")]
            named = len(errors) == 1 and f"Assets/{name}.boxmarch.json" in errors[0]
            if result["set"] or not named or len(result["logged"]) != 1:
                faults.append(f"{name}: set {result['set']}, logged {result['logged']}")
    return faults


def unity_settings() -> dict:
    """{ModelImporter property: C# value} the shipped postprocessor set, run by the harness, on a
    boxmarch UNITY export (the same in every layout of the preset, else AssertionError)."""
    run = unity_import_run()
    settings = {name: dict(result["set"]) for name, result in run.items() if name.startswith("boxmarch_")}
    first = next(iter(settings.values()))
    assert all(s == first for s in settings.values()), settings
    return first


def unreal_constants() -> dict:
    """The module-level constants of the Unreal script (literal values), read with ast."""
    out = {}
    for node in ast.parse(UNREAL_SCRIPT.read_text()).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            name = node.targets[0].id
            if name.isupper():
                out[name] = ast.literal_eval(node.value)
    return out


def unreal_sidecar(**changes) -> dict:
    """The sidecar formats/sidecar.py writes for an UNREAL export (UV_FRAME), with ``changes``."""
    from boxmarch.formats import presets, sidecar

    stats = [{"mesh": "Mixed", "vertices": 72, "boxes": 9, "transform_error": 0.0}]
    return dict(sidecar.describe(presets.PRESETS["UNREAL"], "UV_FRAME", "model.fbx", stats, {}, {}), **changes)


def unreal_import_run(source=None, sidecar=None):
    """The Unreal script ``source`` (None: the shipped one) run against the stub ``unreal`` module
    (tests/engines/unreal_stub.py): ``import_boxmarch_fbx`` on model.fbx with ``sidecar`` (a dict;
    None: :func:`unreal_sidecar`) beside it. Returns (the stub session, what the function returned
    or the exception it raised)."""
    from tests.engines.unreal_stub import unreal_session

    text = UNREAL_SCRIPT.read_text() if source is None else source
    folder = Path(tempfile.mkdtemp(prefix="boxmarch-unreal-"))
    (folder / "model.fbx").write_bytes(b"")
    (folder / "model.boxmarch.json").write_text(json.dumps(unreal_sidecar() if sidecar is None else sidecar))
    namespace = {"__name__": "boxmarch_import"}
    exec(compile(text, str(UNREAL_SCRIPT), "exec"), namespace)  # noqa: S102 (the shipped script)
    with unreal_session() as session:
        try:
            result = namespace["import_boxmarch_fbx"](str(folder / "model.fbx"), "/Game/Boxmarch")
        except Exception as error:  # noqa: BLE001 (returned for the test to judge)
            result = error
    shutil.rmtree(folder)
    return session, result


def unreal_settings(source=None) -> tuple:
    """(import data, LOD 0 build settings) of the one static mesh the script imported and saved,
    as saved, enums by name; AssertionError if it imported or saved anything else."""
    session, result = unreal_import_run(source)
    assert result == ["/Game/Boxmarch/model.model"] and list(session.saved) == result, (result, session.saved)
    import_data, build = session.saved[result[0]]
    return {k: getattr(v, "name", v) for k, v in import_data.items()}, build


def godot3_constants() -> dict:
    """The plug-in's ``const NAME = value`` lines (JSON values) of plugin.gd."""
    text = (GODOT3_ADDON / "plugin.gd").read_text()
    return {name: json.loads(value) for name, value in re.findall(r"^const (\w+) = (.+)$", text, re.M)}

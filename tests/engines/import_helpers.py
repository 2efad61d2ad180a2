"""The engine-side import helpers shipped in engines/, read as source: the settings each one sets
and the sidecar values it accepts. The modelled Unity and Unreal imports (tests/engine_scene.py)
are built from what these return, so a test of the model tests what the helper sets.
Blender-free; the Unity script is compiled with mono's mcs against tests/engines/unity_stub."""
import ast
import json
import re
import shutil
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
UNITY_PACKAGE = REPO / "engines" / "unity" / "com.boxmarch.boxmarch"
UNITY_POSTPROCESSOR = UNITY_PACKAGE / "Editor" / "BoxmarchModelPostprocessor.cs"
UNITY_STUB = Path(__file__).resolve().parent / "unity_stub" / "UnityApiStub.cs"
UNREAL_SCRIPT = REPO / "engines" / "unreal" / "boxmarch_import.py"
UNREAL_MATERIAL = REPO / "engines" / "unreal" / "BoxmarchUVFrame.ush"
UNREAL_DEPTH_OFFSET = REPO / "engines" / "unreal" / "BoxmarchDepthOffset.ush"
GODOT3_ADDON = REPO / "engines" / "godot3" / "addons" / "boxmarch"


def unity_settings(source=None) -> dict:
    """{ModelImporter property: C# value} of every ``importer.X = Y;`` in the postprocessor."""
    text = UNITY_POSTPROCESSOR.read_text() if source is None else source
    return dict(re.findall(r"^\s*importer\.(\w+)\s*=\s*([^;]+);", text, re.M))


def unity_constants() -> dict:
    """The postprocessor's FormatVersion, Preset, SidecarSuffix and LayoutsRead."""
    text = UNITY_POSTPROCESSOR.read_text()
    out = {name: json.loads(value) for name, value in re.findall(r"public const \w+ (\w+) = ([^;]+);", text)}
    layouts = re.search(r"LayoutsRead = \{([^}]*)\}", text).group(1)
    out["LayoutsRead"] = tuple(json.loads(f"[{layouts}]"))
    return out


def compile_unity(source: str, out_dir, extra=(), target="library") -> subprocess.CompletedProcess:
    """mcs run on the stub, the package's other Editor sources and ``source`` (a postprocessor's
    text), and ``extra`` source paths, warnings as errors, into ``out_dir``/boxmarch.dll (or .exe)."""
    path = Path(out_dir) / "BoxmarchModelPostprocessor.cs"
    path.write_text(source)
    others = sorted(p for p in (UNITY_PACKAGE / "Editor").glob("*.cs") if p.name != path.name)
    out = Path(out_dir) / f"boxmarch.{'dll' if target == 'library' else 'exe'}"
    return subprocess.run(["mcs", f"-target:{target}", "-warnaserror+", f"-out:{out}", str(UNITY_STUB),
                           *map(str, others), str(path), *map(str, extra)], capture_output=True, text=True, timeout=60)


def mcs_missing():
    return None if shutil.which("mcs") else "mcs is not installed (apt-get install mono-mcs)"


def unreal_constants() -> dict:
    """The module-level constants of the Unreal script (literal values), read with ast."""
    out = {}
    for node in ast.parse(UNREAL_SCRIPT.read_text()).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            name = node.targets[0].id
            if name.isupper():
                out[name] = ast.literal_eval(node.value)
    return out


def godot3_constants() -> dict:
    """The plug-in's ``const NAME = value`` lines (JSON values) of plugin.gd."""
    text = (GODOT3_ADDON / "plugin.gd").read_text()
    return {name: json.loads(value) for name, value in re.findall(r"^const (\w+) = (.+)$", text, re.M)}

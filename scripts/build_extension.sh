#!/usr/bin/env bash
# Packages the add-on for installation into Blender:
#   dist/boxmarch-0.1.0.zip                   Blender 4.2+ extension (blender_manifest.toml; the
#                                             native module as a platform wheel for Python 3.11)
#   dist/boxmarch-0.1.0-legacy-linux-x64.zip  legacy add-on zip for Blender 3.x (bl_info, _core inside)
# The native module is compiled from this checkout in its own build folder (build/extension: a
# running Python that loaded addon/boxmarch/_core*.so is never touched). The extension is built
# and validated with Blender's own extension tool: `blender --command extension build` when the
# blender on PATH is 4.2 or newer, else the same tool (bl_pkg/cli/blender_ext.py) shipped with the
# bpy module of this Python.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
OUT="${1:-dist}"
cmake -S . -B build/extension -DCMAKE_BUILD_TYPE=Release -DBOXMARCH_BUILD_PYTHON=ON \
  -DPython_EXECUTABLE="$(command -v "$PYTHON")" \
  -Dpybind11_DIR="$("$PYTHON" -c 'import pybind11; print(pybind11.get_cmake_dir())')" >/dev/null
cmake --build build/extension -j2 >/dev/null
NATIVE="$(ls build/extension/_core*.so)"
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
STAGE="$(mktemp -d)"
trap 'rm -rf "$STAGE"' EXIT

"$PYTHON" - "$STAGE" "$OUT" "$NATIVE" <<'PY'
"""Stage the extension (package + wheel) and write the legacy zip."""
import base64, hashlib, pathlib, shutil, sys, sysconfig, tomllib, zipfile

stage, out, native = map(pathlib.Path, sys.argv[1:])
package = pathlib.Path("addon/boxmarch")
manifest = tomllib.loads((package / "blender_manifest.toml").read_text())
version = manifest["version"]
ext_suffix = sysconfig.get_config_var("EXT_SUFFIX")
if ext_suffix != ".cpython-311-x86_64-linux-gnu.so":
    sys.exit(f"build_extension: Blender 3.4 (Debian) to 5.0 run CPython 3.11 on x86-64; this Python builds {ext_suffix}")
assert native.name == f"_core{ext_suffix}", native
# (file, path inside the package): the package, and the shaders the preview compiles at run time
# (installed into the package as the wheel does, see CMakeLists.txt).
sources = [(p, p.relative_to(package)) for p in sorted(package.rglob("*"))
           if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".so"]
sources += [(p, pathlib.Path("shaders") / p.relative_to("shaders")) for p in sorted(pathlib.Path("shaders").rglob("*"))
            if p.is_file()]

# Platform wheel: boxmarch_native/_core*.so (a wheel is a zip with a dist-info and hashed RECORD).
wheel_name = f"boxmarch_native-{version}-cp311-cp311-linux_x86_64.whl"
(stage / "boxmarch" / "wheels").mkdir(parents=True)
dist_info = f"boxmarch_native-{version}.dist-info"
files = {
    "boxmarch_native/__init__.py": b'"""The native core of the boxmarch add-on (boxmarch_native._core)."""\n',
    f"boxmarch_native/_core{ext_suffix}": native.read_bytes(),
    f"{dist_info}/METADATA": f"Metadata-Version: 2.1\nName: boxmarch-native\nVersion: {version}\n"
                             f"Summary: Native core of the boxmarch Blender add-on\nLicense: GPL-3.0-or-later\n".encode(),
    f"{dist_info}/WHEEL": b"Wheel-Version: 1.0\nGenerator: boxmarch build_extension.sh\nRoot-Is-Purelib: false\n"
                          b"Tag: cp311-cp311-linux_x86_64\n",
}
record = []
with zipfile.ZipFile(stage / "boxmarch" / "wheels" / wheel_name, "w", zipfile.ZIP_DEFLATED) as whl:
    for name, data in files.items():
        whl.writestr(name, data)
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{name},sha256={digest},{len(data)}")
    record.append(f"{dist_info}/RECORD,,")
    whl.writestr(f"{dist_info}/RECORD", "\n".join(record) + "\n")
assert manifest["wheels"] == [f"./wheels/{wheel_name}"], "blender_manifest.toml names another wheel"
for src, inside in sources:
    dst = stage / "boxmarch" / inside
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(src, dst)

# Legacy add-on zip for Blender 3.x: the package folder with _core inside, no manifest (4.2+
# would otherwise take it for an extension without its wheel).
legacy = out / f"boxmarch-{version}-legacy-linux-x64.zip"
with zipfile.ZipFile(legacy, "w", zipfile.ZIP_DEFLATED) as z:
    for src, inside in sources:
        if src.name != "blender_manifest.toml":
            z.write(src, f"boxmarch/{inside}")
    z.write(native, f"boxmarch/{native.name}")
print(f"[build_extension] {legacy}", file=sys.stderr)
PY

EXTENSION="$OUT/boxmarch-$("$PYTHON" -c 'import tomllib; print(tomllib.load(open("addon/boxmarch/blender_manifest.toml", "rb"))["version"])').zip"
blender_version="$(blender --version 2>/dev/null | head -1 | awk '{print $2}')" || blender_version=""
if [ -n "$blender_version" ] && "$PYTHON" -c "import sys; v = tuple(map(int, sys.argv[1].split('.')[:2])); sys.exit(v < (4, 2))" "$blender_version"; then
  echo "[build_extension] blender $blender_version --command extension build" >&2
  blender --command extension validate "$STAGE/boxmarch"
  blender --command extension build --source-dir "$STAGE/boxmarch" --output-filepath "$EXTENSION"
else
  TOOL="$("$PYTHON" -c 'import bpy, os; print(os.path.join(bpy.utils.system_resource("SCRIPTS"), "addons_core/bl_pkg/cli/blender_ext.py"))' 2>/dev/null | tail -1)" || TOOL=""
  if [ -z "$TOOL" ] || [ ! -f "$TOOL" ]; then
    echo "[build_extension] no Blender >= 4.2 and no bpy module with the extension tool: extension zip not built" >&2
    exit 1
  fi
  echo "[build_extension] blender ${blender_version:-absent} is older than 4.2: using $TOOL" >&2
  "$PYTHON" "$TOOL" validate "$STAGE/boxmarch"
  "$PYTHON" "$TOOL" build --source-dir "$STAGE/boxmarch" --output-filepath "$EXTENSION"
fi
echo "[build_extension] $EXTENSION" >&2

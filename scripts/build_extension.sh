#!/usr/bin/env bash
# Packages the add-on for installation into Blender:
#   bash scripts/build_extension.sh [OUT]
#     OUT/boxmarch-0.1.0.zip                   Blender 4.2+ extension (blender_manifest.toml; the
#                                              native module as a platform wheel for Python 3.11)
#     OUT/boxmarch-0.1.0-legacy-linux-x64.zip  legacy add-on zip for Blender 3.x (bl_info, _core inside)
#   bash scripts/build_extension.sh --wheels WHEELHOUSE [OUT]
#     OUT/boxmarch-0.1.0-PLATFORM.zip          one extension per platform (--split-platforms), the
#                                              native module taken from each cp311 boxmarch wheel in
#                                              WHEELHOUSE (.github/workflows/wheels.yml's cibuildwheel)
# Without --wheels the native module is compiled from this checkout in its own build folder
# (build/extension: a running Python that loaded addon/boxmarch/_core*.so is never touched). The
# extension is built and validated with Blender's own extension tool: `blender --command extension
# build` when the blender on PATH is 4.2 or newer, else the same tool (bl_pkg/cli/blender_ext.py)
# shipped with the bpy module of this Python.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/environments.sh
PYTHON="$(checkout_python)"  # PYTHON, else the test or the demo environment's
WHEELHOUSE=""
if [ "${1:-}" = "--wheels" ]; then
  WHEELHOUSE="$(cd "${2:?--wheels needs a folder}" && pwd)"
  shift 2
fi
OUT="${1:-dist}"
NATIVE=""
if [ -z "$WHEELHOUSE" ]; then
  # The C++ compiler this Python names (sysconfig CXX), as the set-up's `pip install .` compiles
  # with: the same compiler and flags make the compiler cache's entries from that build hit here.
  CXX="${CXX:-$("$PYTHON" -c 'import sysconfig; print((sysconfig.get_config_var("CXX") or "c++").split()[0])')}" \
  cmake -S . -B build/extension -DCMAKE_BUILD_TYPE=Release -DBOXMARCH_BUILD_PYTHON=ON \
    -DPython_EXECUTABLE="$(command -v "$PYTHON")" \
    -Dpybind11_DIR="$("$PYTHON" -c 'import pybind11; print(pybind11.get_cmake_dir())')" >/dev/null
  cmake --build build/extension -j2 >/dev/null
  NATIVE="$(ls build/extension/_core*.so)"
fi
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
STAGE="$(mktemp -d)"
trap 'rm -rf "$STAGE"' EXIT

"$PYTHON" - "$STAGE" "$OUT" "$NATIVE" "$WHEELHOUSE" <<'PY'
"""Stage the extension (package + one native wheel per platform) and, for a local build, write
the legacy zip."""
import base64, hashlib, pathlib, re, shutil, sys, sysconfig, tomllib, zipfile

stage, out = map(pathlib.Path, sys.argv[1:3])
native, wheelhouse = sys.argv[3], sys.argv[4]
package = pathlib.Path("addon/boxmarch")
manifest_text = (package / "blender_manifest.toml").read_text()
manifest = tomllib.loads(manifest_text)
version = manifest["version"]
# Blender's platform names for the wheel platform tags cibuildwheel writes (and this machine's).
PLATFORMS = [(r"win_amd64", "windows-x64"), (r"macosx_\d+_\d+_arm64", "macos-arm64"),
             (r"macosx_\d+_\d+_x86_64", "macos-x64"), (r"(many)?linux(_\d+_\d+)?_x86_64", "linux-x64")]


def blender_platform(tag):
    for pattern, name in PLATFORMS:
        if re.fullmatch(pattern, tag):
            return name
    sys.exit(f"build_extension: no Blender platform for the wheel platform {tag}")


# (module file name, bytes, wheel platform tag) of each native module.
natives = []
if not wheelhouse:
    ext_suffix = sysconfig.get_config_var("EXT_SUFFIX")
    if ext_suffix != ".cpython-311-x86_64-linux-gnu.so":
        sys.exit(f"build_extension: Blender 3.4 (Debian) to 5.0 run CPython 3.11 on x86-64; this Python builds {ext_suffix}")
    assert pathlib.Path(native).name == f"_core{ext_suffix}", native
    natives.append((f"_core{ext_suffix}", pathlib.Path(native).read_bytes(), "linux_x86_64"))
else:
    for whl in sorted(pathlib.Path(wheelhouse).glob(f"boxmarch-{version}-cp311-cp311-*.whl")):
        tag = whl.stem.split("-")[-1].split(".")[-1]  # manylinux_2_27_x86_64.manylinux_2_28_x86_64: the last
        with zipfile.ZipFile(whl) as z:
            (member,) = [n for n in z.namelist() if re.fullmatch(r"boxmarch/_core\.[^/]+\.(so|pyd)", n)]
            natives.append((member.split("/")[-1], z.read(member), tag))
    if not natives:
        sys.exit(f"build_extension: no boxmarch-{version}-cp311-cp311-*.whl in {wheelhouse}")

# (file, path inside the package): the package, and the shaders the preview compiles at run time
# (installed into the package as the wheel does, see CMakeLists.txt).
sources = [(p, p.relative_to(package)) for p in sorted(package.rglob("*"))
           if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".so"]
sources += [(p, pathlib.Path("shaders") / p.relative_to("shaders")) for p in sorted(pathlib.Path("shaders").rglob("*"))
            if p.is_file()]
for src, inside in sources:
    dst = stage / "boxmarch" / inside
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(src, dst)

# Platform wheels: boxmarch_native/_core* (a wheel is a zip with a dist-info and hashed RECORD).
(stage / "boxmarch" / "wheels").mkdir(parents=True)
dist_info = f"boxmarch_native-{version}.dist-info"
wheel_names = []
for module_name, data, tag in natives:
    wheel_name = f"boxmarch_native-{version}-cp311-cp311-{tag}.whl"
    files = {
        "boxmarch_native/__init__.py": b'"""The native core of the boxmarch add-on (boxmarch_native._core)."""\n',
        f"boxmarch_native/{module_name}": data,
        f"{dist_info}/METADATA": f"Metadata-Version: 2.1\nName: boxmarch-native\nVersion: {version}\n"
                                 f"Summary: Native core of the boxmarch Blender add-on\nLicense: GPL-3.0-or-later\n".encode(),
        f"{dist_info}/WHEEL": f"Wheel-Version: 1.0\nGenerator: boxmarch build_extension.sh\nRoot-Is-Purelib: false\n"
                              f"Tag: cp311-cp311-{tag}\n".encode(),
    }
    record = []
    with zipfile.ZipFile(stage / "boxmarch" / "wheels" / wheel_name, "w", zipfile.ZIP_DEFLATED) as whl:
        for name, content in files.items():
            whl.writestr(name, content)
            digest = base64.urlsafe_b64encode(hashlib.sha256(content).digest()).rstrip(b"=").decode()
            record.append(f"{name},sha256={digest},{len(content)}")
        record.append(f"{dist_info}/RECORD,,")
        whl.writestr(f"{dist_info}/RECORD", "\n".join(record) + "\n")
    wheel_names.append(wheel_name)
if not wheelhouse:
    assert manifest["wheels"] == [f"./wheels/{n}" for n in wheel_names], "blender_manifest.toml names another wheel"
else:  # the staged manifest names every platform's wheel
    platforms = sorted({blender_platform(tag) for _, _, tag in natives})
    staged = re.sub(r"(?m)^platforms = .*$", "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]", manifest_text)
    staged = re.sub(r"(?m)^wheels = .*$", "wheels = [" + ", ".join(f'"./wheels/{n}"' for n in wheel_names) + "]", staged)
    (stage / "boxmarch" / "blender_manifest.toml").write_text(staged)
    print(f"[build_extension] platforms {', '.join(platforms)}", file=sys.stderr)

if not wheelhouse:
    # Legacy add-on zip for Blender 3.x: the package folder with _core inside, no manifest (4.2+
    # would otherwise take it for an extension without its wheel).
    legacy = out / f"boxmarch-{version}-legacy-linux-x64.zip"
    with zipfile.ZipFile(legacy, "w", zipfile.ZIP_DEFLATED) as z:
        for src, inside in sources:
            if src.name != "blender_manifest.toml":
                z.write(src, f"boxmarch/{inside}")
        z.write(native, f"boxmarch/{natives[0][0]}")
    print(f"[build_extension] {legacy}", file=sys.stderr)
PY

EXTENSION="$OUT/boxmarch-$("$PYTHON" -c 'import tomllib; print(tomllib.load(open("addon/boxmarch/blender_manifest.toml", "rb"))["version"])').zip"
SPLIT=()
[ -n "$WHEELHOUSE" ] && SPLIT=(--split-platforms)  # OUT/boxmarch-VERSION-PLATFORM.zip, each with its wheel
blender_version="$(blender --version 2>/dev/null | head -1 | awk '{print $2}')" || blender_version=""
if [ -n "$blender_version" ] && "$PYTHON" -c "import sys; v = tuple(map(int, sys.argv[1].split('.')[:2])); sys.exit(v < (4, 2))" "$blender_version"; then
  echo "[build_extension] blender $blender_version --command extension build" >&2
  blender --command extension validate "$STAGE/boxmarch"
  blender --command extension build --source-dir "$STAGE/boxmarch" --output-filepath "$EXTENSION" "${SPLIT[@]}"
else
  TOOL="$("$PYTHON" -c 'import bpy, os; print(os.path.join(bpy.utils.system_resource("SCRIPTS"), "addons_core/bl_pkg/cli/blender_ext.py"))' 2>/dev/null | tail -1)" || TOOL=""
  if [ -z "$TOOL" ] || [ ! -f "$TOOL" ]; then
    echo "[build_extension] no Blender >= 4.2 and no bpy module with the extension tool: extension zip not built" >&2
    exit 1
  fi
  echo "[build_extension] blender ${blender_version:-absent} is older than 4.2: using $TOOL" >&2
  "$PYTHON" "$TOOL" validate "$STAGE/boxmarch"
  "$PYTHON" "$TOOL" build --source-dir "$STAGE/boxmarch" --output-filepath "$EXTENSION" "${SPLIT[@]}"
fi
echo "[build_extension] $EXTENSION${SPLIT:+ (one per platform)}" >&2

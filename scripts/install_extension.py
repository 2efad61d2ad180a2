"""Installs boxmarch's extension zip (made by scripts/build_extension.sh) into Blender 4.2 or newer
from a script: with a Python that has the bpy module, or inside the Blender program.

    python3 scripts/install_extension.py dist/boxmarch-0.1.0.zip
    blender --background --python scripts/install_extension.py -- dist/boxmarch-0.1.0.zip

Blender's own operator does the work: ``bpy.ops.extensions.package_install_files(filepath=ZIP,
repo="user_default", enable_on_install=True)`` copies the extension into the user repository
(its native wheel into the extension's site-packages) and enables it, as *Install from Disk*
does; the preferences are then saved, so the Blender program starts with it enabled. The bpy
module starts every session from factory settings: there, enable the installed copy with
``bpy.ops.preferences.addon_enable(module="bl_ext.user_default.boxmarch")``. Exit codes: 0
installed, 2 bad input (one line saying why), 1 Blender's operator failed.
"""
import os
import sys

EXTENSION_MODULE = "bl_ext.user_default.boxmarch"


def install(zip_path: str) -> str:
    """Installs and enables the extension at ``zip_path``; returns its module name. Raises
    ValueError (nothing installed) for a missing file or a Blender older than 4.2."""
    import bpy

    if not os.path.isfile(zip_path) or not zip_path.lower().endswith(".zip"):
        raise ValueError(f"{zip_path}: no such .zip file (bash scripts/build_extension.sh makes dist/boxmarch-*.zip)")
    if bpy.app.version < (4, 2, 0):
        raise ValueError(f"Blender {bpy.app.version_string} has no extensions: install the legacy zip "
                         "(dist/boxmarch-*-legacy-*.zip) with Preferences > Add-ons > Install")
    result = bpy.ops.extensions.package_install_files(filepath=os.path.abspath(zip_path), repo="user_default",
                                                      enable_on_install=True)
    if result != {"FINISHED"}:
        raise RuntimeError(f"extensions.package_install_files returned {sorted(result)}")
    bpy.ops.wm.save_userpref()
    return EXTENSION_MODULE


def main() -> int:
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    if len(argv) != 1:
        print("usage: install_extension.py ZIP", file=sys.stderr)
        return 2
    try:
        module = install(argv[0])
    except ModuleNotFoundError as error:
        if error.name != "bpy":
            raise
        print("install_extension: error: this Python has no bpy module: run it with Blender's "
              "(pip install bpy==5.0.* on Python 3.11) or inside the Blender program", file=sys.stderr)
        return 2
    except ValueError as error:
        print(f"install_extension: error: {error}", file=sys.stderr)
        return 2
    print(f"install_extension: installed and enabled {module}")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    # bpy 4.2 and 4.5 (PyPI) crash at exit once an add-on registered classes; inside the Blender
    # program a SystemExit would be swallowed (exit 0): leave with the code either way.
    os._exit(code)

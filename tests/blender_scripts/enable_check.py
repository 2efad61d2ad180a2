"""Run with the bpy module in a new process, on the user configuration install_check.py installed
the extension into: enables it the way docs/OVERVIEW.md says for a fresh session, and writes what happened.
Usage: python enable_check.py -- OUT_JSON"""
import json
import os
import sys
import traceback

out_path = sys.argv[sys.argv.index("--") + 1]
result = {"error": None}
try:
    import bpy
    import addon_utils

    module_name = "bl_ext.user_default.boxmarch"
    result["enabled_at_start"] = addon_utils.check(module_name)[1]
    bpy.ops.preferences.addon_enable(module=module_name)
    result["enabled"] = addon_utils.check(module_name)[1]
    result["operator_registered"] = hasattr(bpy.types, "BOXMARCH_OT_bake")
    result["module_file"] = sys.modules[module_name].__file__
except Exception:
    result["error"] = traceback.format_exc()
with open(out_path, "w") as f:
    json.dump(result, f)
sys.stdout.flush()
sys.stderr.flush()
os._exit(0)  # the bpy modules 4.2 and 4.5 segfault at interpreter exit once the add-on registered

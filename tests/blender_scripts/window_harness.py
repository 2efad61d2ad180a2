"""Start and finish shared by the scripts that run inside a Blender program with a window (under
Xvfb): operators that need a window, such as undo and screenshots, only work once it is up."""
import json
import sys
import traceback


def arguments():
    """The script's arguments after '--'. The first names the folder holding the boxmarch package
    under test, which goes first on sys.path."""
    argv = sys.argv[sys.argv.index("--") + 1:]
    sys.path.insert(0, argv[0])
    return argv


def run_in_window(check, out_path):
    """Once the window is up, call check(report) and write report to out_path as JSON, with
    report['error'] the traceback of what check raised (None if nothing); then quit Blender."""
    import bpy

    def tick():
        report = {"error": None}
        try:
            check(report)
        except Exception:
            report["error"] = traceback.format_exc()
        with open(out_path, "w") as out:
            json.dump(report, out)
        bpy.ops.wm.quit_blender()

    bpy.app.timers.register(tick, first_interval=1.0)

"""Runs the add-on's Blender-facing tests under each Blender release and prints a table.

    .venv-test/bin/python scripts/blender_matrix.py               # 3.4 4.2 4.5 5.0, every Blender-facing test
    .venv-test/bin/python scripts/blender_matrix.py --quick 4.2   # the CI selection under bpy 4.2 (scripts/test.sh)
    .venv-test/bin/python scripts/blender_matrix.py 4.5 -- -x     # arguments after -- go to pytest

3.4 is Debian's Blender program (tests marked ``blender_program``); 4.2 and later are PyPI's bpy
module (tests marked ``bpy``), the release in this Python when it matches, else one installed by
scripts/install_bpy.sh into its own folder (.cache/bpy-MAJOR.MINOR) and put first on the path by
BOXMARCH_BPY_PATH (tests/conftest.py). Every run uses this Python (the test environment's,
.venv-test, made by scripts/setup.sh). Exit status 1 when any release failed.
"""
import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
VERSIONS = ["3.4", "4.2", "4.5", "5.0"]
# --quick: the add-on proved on a release in about a minute: registration and the bake operator,
# the submesh tools, the export presets, the offscreen preview against the CPU reference (and a
# broken user SDF named by its line), the hidden-box pre-pass and resolved passes, `python -m boxmarch` (exit codes 0 and 2), and the 4.2+
# extension zip validated, installed and enabled by that release's own extension tool.
QUICK = [
    "tests/test_blender.py::test_operator_is_registered_for_search_and_menus",
    "tests/test_blender.py::test_bake_operator_decodes_to_box_centres",
    "tests/test_blender.py::test_rebake_skips_unchanged_submeshes",
    "tests/test_blender.py::test_edit_mode_bakes_submeshes_with_a_selected_vertex",
    "tests/test_tools_blender.py::test_tools_are_in_the_menus_and_the_panel",
    "tests/test_tools_blender.py::test_select_linked_submeshes_in_multi_object_edit_mode",
    "tests/test_tools_blender.py::test_dedup_only_among_selected_submeshes_in_multi_object_edit",
    "tests/test_tools_blender.py::test_merge_per_submesh_equals_blenders_merge_of_each_submesh",
    "tests/test_export.py",
    "tests/test_preview_blender.py",
    "tests/test_preview.py::test_preview_matches_cpu_reference",
    "tests/test_preview.py::test_user_sdf_error_names_line_and_falls_back_to_outline",
    "tests/test_preview_occluders.py",
    "tests/test_cli.py::test_module_bake_export_pipeline_on_a_file",
    "tests/test_cli.py::test_module_failure_report_is_json_when_asked",
    "tests/test_install.py::test_extension_installs_into_clean_blender_4_2_or_later_and_bakes",
]
SUMMARY = re.compile(r"(\d+) (passed|failed|skipped|errors?|deselected|xfailed|xpassed)")


def bpy_folder(version):
    """None when this Python's own bpy is that release, else the folder install_bpy.sh fills."""
    own = subprocess.run([sys.executable, "-c", "import bpy; print('%d.%d' % bpy.app.version[:2])"],
                         capture_output=True, text=True, env=clean_env())
    if own.returncode == 0 and own.stdout.strip().splitlines()[-1:] == [version]:
        return None
    return subprocess.run(["bash", str(REPO / "scripts" / "install_bpy.sh"), version], check=True,
                          env=dict(os.environ, PYTHON=sys.executable), capture_output=True, text=True).stdout.strip()


def clean_env():
    return {k: v for k, v in os.environ.items() if k != "BOXMARCH_BPY_PATH"}


def run(version, quick, pytest_args):
    env = clean_env()
    if version == "3.4":
        selection = ["-m", "blender_program"]
    else:
        folder = bpy_folder(version)
        if folder:
            env["BOXMARCH_BPY_PATH"] = folder
        selection = ["-m", "bpy", *(QUICK if quick else [])]
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *selection, *pytest_args]
    start = time.monotonic()
    proc = subprocess.run(command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seconds = time.monotonic() - start
    sys.stdout.write(proc.stdout)
    last = next((line for line in reversed(proc.stdout.splitlines()) if SUMMARY.search(line)), "")
    counts = {word.rstrip("s") if word.startswith("error") else word: int(n) for n, word in SUMMARY.findall(last)}
    return {"version": version, "selection": "quick" if quick and version != "3.4" else "all",
            "passed": counts.get("passed", 0), "failed": counts.get("failed", 0),
            "errors": counts.get("error", 0), "skipped": counts.get("skipped", 0),
            "seconds": seconds, "exit": proc.returncode}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("versions", nargs="*", default=VERSIONS, choices=VERSIONS, metavar="VERSION")
    parser.add_argument("--quick", action="store_true", help="the CI selection (bpy releases only)")
    argv = sys.argv[1:]
    pytest_args = argv[argv.index("--") + 1:] if "--" in argv else []
    args = parser.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    rows = [run(version, args.quick, pytest_args) for version in args.versions]
    print("\n| Blender | tests | passed | failed | errors | skipped | time (s) | exit |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['version']} | {r['selection']} | {r['passed']} | {r['failed']} | {r['errors']} | "
              f"{r['skipped']} | {r['seconds']:.0f} | {r['exit']} |")
    print(f"blender_matrix: {sum(r['passed'] for r in rows)} passed, "
          f"{sum(r['failed'] + r['errors'] for r in rows)} failed")
    return 0 if all(r["exit"] == 0 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

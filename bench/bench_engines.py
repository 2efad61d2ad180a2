"""Engine figures: per engine and layout, what arrives after the engine's importer and how close
the shipped shader's pixels land, on the mixed scene of tests/engine_scene.py (1 x 0.6 x 0.2,
0.02 x 0.02 x 0.1 and 5 x 5 x 5 boxes).

Decode columns: worst origin error / largest half-extent, axis error (1 - cos), half-extent
error / half-extent, decoding what the engine holds with docs/ENGINES.md's formulas against the
generating boxes. Render columns (real engines only): the tightest tolerance in pixels at which
the raymarched boxes at 0.6 of each box's half-extents cover their projected silhouettes (the
tests require <= 1), for the shipped shader and for its negative controls: the frame replaced by the
identity, and (three.js) the offset channels zeroed.
Unity and Unreal do not run here: their rows decode the exported FBX numbers through the
documented importer rules (tests/test_engine_fbx_models.py).

Second table: the FBX exports read by ufbx (Godot 4.3+'s loader) and Assimp, the libraries
engines load FBX with (tests/test_engine_fbx_libraries.py), each followed by the engine's
documented import rules and the documented decode: the static mixed scene (UNITY, UNREAL), the
skinned rig (UNITY) at rest and posed by ufbx's skinning. *control*: the origin error with the
frame dropped (identity quaternion or identity normal / tangent; rest frame under the pose),
which the tests require above 0.1.

    python3 -m bench.bench_engines
"""
import os
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
import bpy  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch.export import scene as export_scene  # noqa: E402
from bench.common import table  # noqa: E402
from tests.engine_scene import (TO_Y_UP, baked_scene, box_of_vertex, decode_normal_frame,  # noqa: E402
                                decode_uv_frame, frame_and_size_errors, imported, silhouettes, table_texels, UNITY, UNREAL)
from tests.engines import fbx_libraries, godot3, threejs, tightest_tolerance  # noqa: E402
from tests.fbx_reader import read_fbx_geometry  # noqa: E402
from tests import test_engine_fbx_libraries as library_test  # noqa: E402
from tests import test_engine_godot3 as godot_test  # noqa: E402
from tests import test_engine_threejs as three_test  # noqa: E402


def fmt(x):
    return f"{x:.1e}"


def threejs_rows(ob, scene, folder, release):
    centres, sizes, rotations = scene
    rows = []
    t = threejs.RELEASES[release].texcoords
    for layout in ("NORMAL_FRAME", "UV_FRAME"):
        path = os.path.join(folder, f"{layout}.glb")
        report = export_scene.export_objects(bpy.context, [ob], "GLTF", path, layout)
        glb = open(path, "rb").read()
        start = time.perf_counter()
        jobs = [threejs.load_job()]
        if layout == "NORMAL_FRAME":  # the shipped material reads the NORMAL_FRAME layout
            jobs += [threejs.render_job(three_test.setup_js(three_test.BOX_MAP, tamper), three_test.W, three_test.H,
                                        three_test.WIDE)
                     for tamper in ("", three_test.IDENTITY_FRAME, three_test.offset_zeroed(release))]
        (mesh,), *shots = threejs.run_jobs(glb, jobs, threejs.shipped_material(release), release)
        a = mesh["attributes"]
        box = box_of_vertex(a["position"], centres, sizes, rotations, TO_Y_UP)
        if layout == "NORMAL_FRAME":
            offset = np.concatenate([a[t[1]], a[t[2]][:, :1]], axis=1)
            half = np.concatenate([a[t[3]], a[t[4]][:, :1]], axis=1)
            decoded = decode_normal_frame(a["position"], a["normal"], a["tangent"], offset, half)
        else:
            decoded = decode_uv_frame(a["position"], [a[name] for name in t[1:7]])[:3]
        errors = frame_and_size_errors(*decoded, box, centres, sizes, rotations, TO_Y_UP)
        tols = [tightest_tolerance(three_test.covered(shot),
                                   silhouettes(shot, centres, three_test.INNER * sizes, rotations, TO_Y_UP))
                for shot in shots] or ["-", "-", "-"]
        engine = f"three.js r{threejs.RELEASES[release].revision} ({threejs.RELEASES[release].context})"
        rows.append([engine, "GLTF", layout, ", ".join(report["meshes"][0]["channels"]),
                     *map(fmt, errors), *tols, f"{time.perf_counter() - start:.1f}"])
    return rows


def godot_rows(ob, scene, folder):
    centres, sizes, rotations = scene
    path = os.path.join(folder, "godot.glb")
    report = export_scene.export_objects(bpy.context, [ob], "GODOT3", path)
    table_text = open(report["table"]).read()
    rows = []
    for compress in (False, True):
        start = time.perf_counter()
        project = os.path.join(folder, f"godot-{compress}")
        godot3.import_gltf(open(path, "rb").read(), project, compress=compress,
                           extra_files={"model.boxes.tres": table_text.encode()})
        (s,) = godot3.dump_arrays(project)
        box = box_of_vertex(s["vertex"], centres, sizes, rotations, TO_Y_UP)
        index = np.clip(np.rint(s["color"][:, 3]).astype(int), 0, len(centres) - 1)
        half = table_texels(table_text)[index, :3]
        decoded = decode_normal_frame(s["vertex"], s["normal"], s["tangent"], s["color"][:, :3], half)
        errors = frame_and_size_errors(*decoded, box, centres, sizes, rotations, TO_Y_UP)
        render = negative = "-"
        if not compress:
            uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
            tols = []
            for replacement in (None, godot3.IDENTITY_FRAME):
                shot = godot3.render(project, godot_test.shader(replacement), width=godot_test.W,
                                     height=godot_test.H, camera=godot_test.WIDE, uniforms=uniforms)
                expected = silhouettes(shot, centres, godot_test.INNER * sizes, rotations, TO_Y_UP)
                tols.append(tightest_tolerance(shot.pixels[..., :3].max(axis=2) > 20, expected))
            render, negative = tols
        label = "compress on (default)" if compress else "compress off"
        rows.append([f"Godot 3.2, {label}", "GODOT3", "NORMAL_COLOR", ", ".join(report["meshes"][0]["channels"]),
                     *map(fmt, errors), render, negative, "-", f"{time.perf_counter() - start:.1f}"])
    return rows


def fbx_rows(ob, scene, folder):
    centres, sizes, rotations = scene
    rows = []
    for preset, engine, compressed in (("UNITY", UNITY, (2, 3, 4, 5, 6)),
                                       ("UNREAL", UNREAL, (1, 2, 3, 4, 5, 6))):
        path = os.path.join(folder, f"{preset}.fbx")
        report = export_scene.export_objects(bpy.context, [ob], preset, path)
        raw = read_fbx_geometry(path)
        for label, halves in (("full precision", ()), ("default (half UVs)", compressed)):
            start = time.perf_counter()
            positions, uvs = imported(raw, engine, halves)
            box = box_of_vertex(positions, centres, sizes, rotations, engine["to_engine"])
            origins, axes, half, _index = decode_uv_frame(positions, uvs)
            scale = engine["scale"]
            errors = frame_and_size_errors(origins, axes, half, box, centres * scale, sizes * scale, rotations,
                                           engine["to_engine"] / scale)
            rows.append([f"{preset.title()} (model), {label}", preset, "UV_FRAME",
                         ", ".join(report["meshes"][0]["channels"]), *map(fmt, errors), "-", "-", "-",
                         f"{time.perf_counter() - start:.1f}"])
    return rows


def library_rows(folder):
    """Rows of the FBX libraries' table (ufbx and Assimp where installed)."""
    import pathlib

    files = library_test.export_files(bpy, pathlib.Path(folder))
    names = {}
    if fbx_libraries.ufbx_available() is None:
        version = str(fbx_libraries.read_with_ufbx(files["UNITY"], folder)["ufbx_version"])
        names["ufbx"] = f"ufbx {version} (PyPI ufbx 0.0.5)"
    if fbx_libraries.assimp_available() is None:
        names["assimp"] = f"Assimp {fbx_libraries.assimp_version()}"
    rows = []
    for library, name in names.items():
        for preset, engine in library_test.ENGINES.items():
            start = time.perf_counter()
            raw = library_test.library_read(library, files[preset], folder)
            errors = library_test.static_errors(raw, engine, files["scene"])[0]
            control = library_test.static_errors(raw, engine, files["scene"], frame=False)[0][0]
            rows.append([name, preset, "UV_FRAME, static", *map(fmt, errors), fmt(control),
                         f"{time.perf_counter() - start:.2f}"])
        start = time.perf_counter()
        raw = library_test.library_read(library, files["skinned"], folder)
        rows.append([name, "UNITY", "NORMAL_FRAME, skinned at rest", *map(fmt, library_test.rest_errors(raw)),
                     fmt(library_test.rest_errors(raw, frame=False)[0]), f"{time.perf_counter() - start:.2f}"])
        if library == "ufbx":
            start = time.perf_counter()
            errors, rest_frame = library_test.posed_errors(files["skinned"], files["posed"], folder, files["motions"])
            rows.append([name, "UNITY", "NORMAL_FRAME, posed by ufbx", *map(fmt, errors), fmt(rest_frame[0]),
                         f"{time.perf_counter() - start:.2f}"])
    return rows


def main():
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ob, centres, sizes, rotations = baked_scene(bpy)
    scene = (centres, sizes, rotations)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for release in threejs.RELEASES:
            if threejs.available(release) is None:
                rows += threejs_rows(ob, scene, folder, release)
        if godot3.available() is None:
            rows += godot_rows(ob, scene, folder)
        rows += fbx_rows(ob, scene, folder)
        libraries = library_rows(folder)
    print(table(["engine", "preset", "layout", "channels", "origin err", "axis err", "half err",
                 "render px", "identity px", "offset zeroed px", "s"], rows))
    print()
    print(table(["library", "preset", "layout, scene", "origin err", "axis err", "half err", "control", "s"],
                libraries))


if __name__ == "__main__":
    main()

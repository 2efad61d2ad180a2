"""Export benchmark inside Blender (the bpy module): each engine preset on N baked boxes.

For FLOAT_COLOR and BYTE_COLOR bakes it prints the export time of every preset (best of 3; each
in the CLASSIC layout where it carries it, else its default), the time of the FBX frame patch
alone (formats/fbx.replace_frame on the UNITY NORMAL_FRAME file) and the worst decode error of
the exported file, read back without Blender's importers (the .glb with
tests/gltf_reader.py, the .fbx's raw numbers with Blender's FBX parser) and decoded with the
shader's formula in the target's frame (glTF: as stored; Unity: x negated, as its FBX importer
does). It then simulates what Unity stores by default (docs/EXPORT.md): vertex compression to
16-bit floats of TexCoord2 (the quaternion's z, w) and of the colour when kept as floats, or the
colour as Color32 bytes.

    python3 -m bench.bench_export [N ...]     (default: 1000 16000)
"""
import os
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
import bpy  # noqa: E402
from tests.fbx_reader import read_fbx_geometry  # noqa: E402
from tests.gltf_reader import read_glb  # noqa: E402

import boxmarch  # noqa: E402
from bench.common import best_of, boxes_object, table  # noqa: E402
from boxmarch.export import scene as export_scene  # noqa: E402
from boxmarch.formats import fbx, presets  # noqa: E402


def shader_origin(position, rgba, q):
    f = (rgba[:, :3] * 2.0 - 1.0) / rgba[:, 3:4]
    u, w = q[:, :3], q[:, 3:4]
    return position + f + 2.0 * np.cross(u, np.cross(u, f) + w * f)


def worst(origin, reference, half):
    return float((np.linalg.norm(origin - reference, axis=1) / half).max())


def measure(count, encoding, folder):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ob, _, _ = boxes_object(bpy, count, seed=3)
    from boxmarch import mesh_io

    prepared = mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings(encoding=encoding, incremental=False))
    prepared.write()
    r = prepared.result
    origins, half = r.origins, r.half_extents.max(axis=1)  # the bake's centres of the stored boxes
    positions = np.empty(len(ob.data.vertices) * 3, np.float32)
    ob.data.vertices.foreach_get("co", positions)
    positions = positions.reshape(-1, 3)
    paths = {p: os.path.join(folder, f"b{count}_{p}{presets.PRESETS[p].extension}") for p in presets.PRESETS}
    # CLASSIC where a preset carries it: the layout whose decode shader_origin writes out
    layout = {p: "CLASSIC" if "CLASSIC" in presets.PRESETS[p].layouts else None for p in presets.PRESETS}
    seconds = {p: best_of(3, lambda p=p: export_scene.export_objects(bpy.context, [ob], p, paths[p], layout[p]))
               for p in presets.PRESETS}

    gltf_axes = presets.PRESETS["GLTF"].axes
    lookup = {tuple(v): i for i, v in enumerate((positions.astype(np.float64) @ gltf_axes.T).astype(np.float32).tolist())}
    gltf_error = 0.0
    for primitive in read_glb(paths["GLTF"])[0]["primitives"]:
        box = np.array([lookup[tuple(v)] for v in primitive["POSITION"].astype(np.float32).tolist()]) // 8
        q = np.concatenate([primitive["TEXCOORD_1"], primitive["TEXCOORD_2"]], axis=1)
        gltf_error = max(gltf_error, worst(shader_origin(primitive["POSITION"], primitive["COLOR_0"], q),
                                           origins[box] @ gltf_axes.T, half[box]))

    raw = read_fbx_geometry(paths["UNITY"])
    box = raw["vertex"] // 8
    unity_reference = origins[box] @ presets.PRESETS["UNITY"].axes.T
    position = raw["position"] * [-1.0, 1.0, 1.0]  # Unity's importer negates x
    colour, xy, zw = raw["BoxOffset"], raw["BoxQuatXY"], raw["BoxQuatZW"]
    half16 = lambda a: a.astype(np.float16).astype(np.float64)
    color32 = lambda a: np.rint(np.clip(a, 0, 1) * 255) / 255
    unity = {
        "file": worst(shader_origin(position, colour, np.concatenate([xy, zw], 1)), unity_reference, half[box]),
        "TexCoord2 fp16": worst(shader_origin(position, colour, np.concatenate([xy, half16(zw)], 1)), unity_reference, half[box]),
        "colour fp16": worst(shader_origin(position, half16(colour), np.concatenate([xy, zw], 1)), unity_reference, half[box]),
        "colour Color32": worst(shader_origin(position, color32(colour), np.concatenate([xy, zw], 1)), unity_reference, half[box]),
    }
    seconds["patch"] = frame_patch_seconds(ob, os.path.join(folder, f"b{count}_frame.fbx"))
    return seconds, gltf_error, unity, os.path.getsize(paths["GLTF"]), os.path.getsize(paths["UNITY"])


def frame_patch_seconds(ob, path):
    """Best of 3 of the FBX frame patch (formats/fbx.replace_frame: read, patch, write the whole
    file) on the UNITY NORMAL_FRAME export, writing the file's own frame back."""
    export_scene.export_objects(bpy.context, [ob], "UNITY", path, layout="NORMAL_FRAME")
    raw = read_fbx_geometry(path)
    frames = {"NORMAL": raw["normal"], "TANGENT": raw["tangent"], "BINORMAL": raw["binormal"]}
    return best_of(3, lambda: fbx.replace_frame(path, {ob.data.name: frames}))


def main():
    counts = [int(a) for a in sys.argv[1:]] or [1000, 16000]
    boxmarch.register()
    rows, unity_rows = [], []
    with tempfile.TemporaryDirectory() as folder:
        for count in counts:
            for encoding in ("FLOAT_COLOR", "BYTE_COLOR"):
                seconds, gltf_error, unity, glb_size, fbx_size = measure(count, encoding, folder)
                rows.append([f"{count:,}", encoding, f"{seconds['GLTF'] * 1e3:.0f}", f"{seconds['UNITY'] * 1e3:.0f}",
                             f"{seconds['BLENDER'] * 1e3:.0f}", f"{seconds['patch'] * 1e3:.0f}",
                             f"{glb_size / 1e6:.1f}", f"{fbx_size / 1e6:.1f}",
                             f"{gltf_error:.1e}", f"{unity['file']:.1e}"])
                unity_rows.append([f"{count:,}", encoding, *(f"{unity[k]:.1e}" for k in
                                                             ("file", "TexCoord2 fp16", "colour fp16", "colour Color32"))])
    print(f"Blender {bpy.app.version_string}; decode error = worst |decoded - baked centre| / largest half-extent")
    print(table(["boxes", "bake", "GLTF ms", "UNITY ms", "BLENDER ms", "FBX frame patch ms", ".glb MB", ".fbx MB",
                 "glTF decode (glb)", "Unity decode (fbx)"], rows))
    print()
    print("What Unity may store (simulated from the .fbx numbers):")
    print(table(["boxes", "bake", "as in file", "TexCoord2 as fp16", "colour as fp16", "colour as Color32"], unity_rows))


if __name__ == "__main__":
    main()

"""Bytes per box in every engine export (bpy module): each preset and layout on N baked boxes.

Per preset and layout it prints the vertices per box the file holds (a .glb's accessors; an
FBX's distinct corner tuples, what an importer welds its per-corner data to), the bytes of one
vertex over its attributes, the bytes per box (vertices x vertex bytes + index bytes, and the
whole file over the boxes) and the export time (best of 3). Counted from the written file with
the tests' own readers (tests/helpers/file_vertices.py), not from the export code.

Two meshes of boxes: ``smooth`` (faces smooth, no UV map: as scripts and the demos make them)
and ``flat`` (flat faces, as Add > Mesh > Cube makes them). The bake adds the UV map the layout
numbering needs when a mesh has none.

    python3 -m bench.bench_bytes [N]     (default: 1000)
"""
import os
import sys
import tempfile

import bpy  # noqa: F401  (before tests.fbx_reader)
import numpy as np

import boxmarch
from bench.common import best_of, boxes_object, table
from boxmarch import mesh_io
from boxmarch.export import scene as export_scene
from boxmarch.formats import presets
from tests.helpers.file_vertices import model_counts


def baked_boxes(count, shading):
    """A selected mesh object of ``count`` random boxes, faces ``shading`` ('smooth' or 'flat'), baked."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ob, _, _ = boxes_object(bpy, count, seed=3)
    if shading == "flat":
        ob.data.polygons.foreach_set("use_smooth", np.zeros(len(ob.data.polygons), bool))
    prepared = mesh_io.prepare_bake(ob.data, mesh_io.BakeSettings(incremental=False))
    prepared.write()
    return ob


def rows_for(count, shading, folder):
    ob = baked_boxes(count, shading)
    rows = []
    for name, preset in presets.PRESETS.items():
        if preset.raw_blend:
            continue
        for layout in preset.layouts:
            path = os.path.join(folder, f"{name}_{layout}{preset.extension}")
            seconds = best_of(3, lambda: export_scene.export_objects(bpy.context, [ob], name, path, layout))
            c = model_counts(path)
            per_box = (c["vertices"] * c["vertex_bytes"] + c["index_bytes"]) / count
            rows.append([shading, name, layout, f"{c['vertices'] / count:.1f}", str(c["vertex_bytes"]),
                         f"{c['index_bytes'] / count:.0f}", f"{per_box:,.0f}", f"{c['file_bytes'] / count:,.0f}",
                         f"{seconds * 1e3:.0f}"])
    return rows


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    boxmarch.register()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for shading in ("smooth", "flat"):
            rows += rows_for(count, shading, folder)
    print(f"Blender {bpy.app.version_string}; {count:,} boxes; FBX vertices: distinct corner tuples, float32 each")
    print(table(["faces", "preset", "layout", "vertices/box", "bytes/vertex", "index bytes/box",
                 "vertex+index bytes/box", "file bytes/box", "export ms"], rows))
    sys.stdout.flush()
    os._exit(0)  # bpy wheels may crash at exit once the add-on registered (docs/NOTES)


if __name__ == "__main__":
    main()

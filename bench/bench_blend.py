"""What blending each box into its parent costs: SDF evaluations per pixel in the viewport
preview (bpy module, offscreen, Mesa llvmpipe), the same chain drawn with its per-box shapes
alone (PER_BOX) and blended into each parent (PER_BOX_BLEND).

Scene: LINKS unit boxes along x, faces touching, each drawn as its sphere (shape id 1), box i the
parent of box i + 1, blend radius 0.3; seen from the side at 640 x 360. The preview's STEPS
output sums map() calls over every fragment of a pixel. A box with a parent evaluates two SDFs
per map() call (its own shape and its parent's), the root one; the root is not grown and its map()
is the same in both modes, so its calls are measured alone (the root box drawn by itself) and
SDF evaluations = 2 x calls(all) - calls(root).

    python3 -m bench.bench_blend [--links N] [--picture docs/blend_chain.png]
"""
import argparse

import numpy as np

import bpy  # noqa: E402
import mathutils  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import bake_job, mesh_io, preview, scenes  # noqa: E402
from bench.common import table  # noqa: E402
from scripts.chain_arm import save_side_by_side  # noqa: E402

W, H = 640, 360
BLEND = 0.3


def chain_object(name, links, parents):
    centres = np.stack([np.arange(links, dtype=float), np.zeros(links), np.zeros(links)], 1)
    arrays = scenes.box_arrays(centres, 1.0, np.eye(3))
    mesh = mesh_io.new_mesh(name, arrays[0], arrays[2], arrays[3], arrays[4])
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    mesh.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set("value", np.ones(8 * links, np.int32))
    if parents:
        mesh.attributes.new("boxmarch_parent", "INT", "POINT").data.foreach_set(
            "value", np.repeat(np.arange(-1, links - 1), 8).astype(np.int32))
    bake_job.bake_meshes([mesh], mesh_io.BakeSettings())
    ob.boxmarch.preview = True
    ob.boxmarch.blend_radius = BLEND
    return ob


def steps(scene, camera, ob, sdf):
    ob.boxmarch.sdf = sdf
    return preview.render(scene, camera, W, H, output="STEPS")[0][..., 0].astype(np.float64)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--links", type=int, default=8)
    parser.add_argument("--picture")
    args = parser.parse_args()
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    chain = chain_object("chain", args.links, parents=True)
    root = chain_object("root", 1, parents=False)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    middle = mathutils.Vector(((args.links - 1) / 2, 0.0, 0.0))
    camera.location = middle + mathutils.Vector((0.0, -1.7 * args.links, 0.4 * args.links))
    camera.rotation_euler = (middle - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    bpy.context.view_layer.update()

    root.hide_viewport = True
    bpy.context.view_layer.update()
    images = {}
    for sdf in ("PER_BOX", "PER_BOX_BLEND"):
        chain.boxmarch.sdf = sdf
        images[sdf] = preview.render(scene, camera, W, H)
    calls = {sdf: steps(scene, camera, chain, sdf) for sdf in ("PER_BOX", "PER_BOX_BLEND")}
    chain.hide_viewport, root.hide_viewport = True, False
    bpy.context.view_layer.update()
    root_calls = steps(scene, camera, root, "PER_BOX")
    evaluations = {"PER_BOX": calls["PER_BOX"], "PER_BOX_BLEND": 2 * calls["PER_BOX_BLEND"] - root_calls}
    rows = []
    for sdf in ("PER_BOX", "PER_BOX_BLEND"):
        covered = images[sdf][1] < 1.0
        drawn = calls[sdf] > 0
        e = evaluations[sdf]
        rows.append((sdf, f"{covered.sum():,}", f"{drawn.sum():,}", f"{calls[sdf][covered].mean():.2f}",
                     f"{e[covered].mean():.2f}", f"{np.percentile(e[covered], 99):.0f}", f"{e.sum():,.0f}"))
    print(f"{args.links} links, blend radius {BLEND}, {W} x {H}")
    print(table(["map()", "covered px", "drawn px", "map() calls / covered px", "SDF evaluations / covered px",
                 "p99", "SDF evaluations, frame"], rows))
    if args.picture:
        save_side_by_side(bpy, images["PER_BOX"][0], images["PER_BOX_BLEND"][0], args.picture)


if __name__ == "__main__":
    main()

"""Input of bench/bench_gpu_frame.py: what the viewport preview uploads for each scene, and the
CPU reference, written as one .npz per scene so that a machine without Blender can draw it.

Scenes (bench_gpu_cost.scenes_to_measure, their cameras made 16:9): cloud (the 16,000-box
world, SPHERE, camera inside), chain side and chain down the arm (scripts/chain_arm.py's links,
LINK), pile (4,000 links, seen through). Each is baked by the add-on's operator in the bpy module
and read back through the preview's own functions: preview/mesh_data.py (CLASSIC layout's vertex
inputs, file and octant triangle orders) and preview/draw.py (the uniform block). The shader
sources are the preview's (formats/shader_sources.py) behind the declarations Blender's GL backend
generates from its create-info, with and without the depth_greater declaration; the naive
full-screen raymarch (naive_fullscreen.frag.glsl) is assembled as bench_preview.py compiles it.
The CPU reference (core.render_boxes, every quality of QUALITIES) at REFERENCE_SIZE.

    PYTHONPATH=addon python3 -m bench.gpu_frame_data OUTDIR [--chains 1000,10000,100000]  # bpy 5.0.1
"""
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

from boxmarch.formats import shader_sources  # noqa: E402

SCENES = ("cloud", "chain side", "chain down the arm", "pile", "pile of 500", "pile of 1000", "pile of 2000")
ASPECT = (16, 9)
REFERENCE_SIZE = (960, 540)
SIZES = ((960, 540), (1920, 1080))
QUALITIES = (1.0, 0.5, 0.25)
BASE_COLOR = (0.8, 0.8, 0.8, 1.0)
GL_VERSION = "430 core"  # what Blender's GL backend asks for


def naive_fragment_source() -> str:
    """The naive full-screen raymarch with the declarations bench_preview.py's create-info makes
    (push constants and sampler as plain uniforms)."""
    header = "\n".join([f"#version {GL_VERSION}", "uniform mat4 clip_to_object;", "uniform vec4 march;",
                        "uniform ivec4 sizes;", "uniform sampler2D boxes;",
                        "layout(location = 0) out vec4 frag_color;", ""])
    return header + "\n".join([shader_sources.read_glsl("decode.glsl"), shader_sources.read_glsl("sdf.glsl"),
                               (HERE / "naive_fullscreen.frag.glsl").read_text()])


NAIVE_VERTEX_SOURCE = (f"#version {GL_VERSION}\nlayout(location = 0) in vec2 pos;\n"
                       "void main() { gl_Position = vec4(pos, 0.0, 1.0); }\n")


def stage_sources(sdf: str) -> dict:
    """Every GLSL stage the harness compiles for a scene of preset ``sdf``."""
    fragment = shader_sources.fragment_source(sdf)
    declared = shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION, "GREATER") + fragment
    return {"vertex": shader_sources.gl_declarations("vert", "CLASSIC", GL_VERSION) + shader_sources.vertex_source("CLASSIC"),
            "fragment_depth_greater": declared,
            "fragment_undeclared": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION) + fragment,
            # the boxes holding the eye (draw.py draws them apart in a perspective view)
            "fragment_eye_boxes": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION, "ANY")
            + shader_sources.fragment_source(sdf, eye_boxes=True),
            # diagnostic: the marched depth not written (the face's stays), so early depth testing is
            # certainly on: shows what the GPU's early test can skip (the depth it leaves is wrong)
            "fragment_face_depth": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION)
            + fragment.replace("gl_FragDepth = ", "float marched_depth = "),
            # diagnostics: the declaration under GLSL 4.50, and with the extension named
            "fragment_depth_greater_450": declared.replace(f"#version {GL_VERSION}", "#version 450 core", 1),
            "fragment_depth_greater_extension": declared.replace(
                f"#version {GL_VERSION}\n", f"#version {GL_VERSION}\n#extension GL_ARB_conservative_depth : enable\n", 1),
            # diagnostic: `discard` replaced by writing the cleared colour and depth (the same
            # picture in a framebuffer cleared to 0 and 1.0; not in Blender's viewport)
            **{f"fragment_{kind}_no_discard": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION, depth_write)
               + fragment.replace("discard;", "{ gl_FragDepth = 1.0; frag_color = vec4(0.0); return; }")
               for kind, depth_write in (("depth_greater", "GREATER"), ("undeclared", None))},
            "naive_vertex": NAIVE_VERTEX_SOURCE, "naive_fragment": naive_fragment_source(),
            # the hidden-box pre-pass and the resolved passes (bench/gl_preview.py)
            "fragment_resolved": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION, resolved=True)
            + shader_sources.fragment_source(sdf, resolved=True),
            "occluder_vertex": shader_sources.gl_declarations("vert", "CLASSIC", GL_VERSION)
            + shader_sources.vertex_source("CLASSIC", occluder=True),
            "occluder_fragment": shader_sources.gl_declarations("frag", "CLASSIC", GL_VERSION)
            + shader_sources.OCCLUDER_FRAGMENT_SOURCE,
            **{f"fullscreen_{stage}": shader_sources.fullscreen_declarations(stage) + shader_sources.fullscreen_source(stage)
               for stage in ("vertex", "resolve_depth", "composite")}}


def widescreen(camera):
    """(object_to_clip, object_to_view) of a square camera of bench_gpu_cost made ASPECT wide:
    the same vertical field of view."""
    to_clip, to_view, _eye = camera
    projection = to_clip @ np.linalg.inv(to_view)
    projection[0, 0] *= ASPECT[1] / ASPECT[0]
    return projection @ to_view, to_view


def preview_facts(baked, settings, to_clip, to_view) -> dict:
    """What draw_object decides for the object (bench/gl_preview.py draws as it does): the
    pre-pass's draws and shape id (occlusion.py), whether back faces may be culled and are the
    front ones (a mirroring matrix), and its boxes' layers over the view at each size
    (mesh_data.layers_over_view: the pre-pass from occlusion.MIN_LAYERS on, the resolved passes
    from resolve.MIN_OVERDRAW on)."""
    from boxmarch.preview import mesh_data, occlusion, resolve

    facts = {"occluder_count": occlusion.occluder_count(settings.sdf), "occluder_shape_id": occlusion.shape_id(settings.sdf),
             "outward": bool(baked.outward), "mirrored": bool(np.linalg.det(to_view[:3, :3]) < 0.0),
             "min_overdraw": resolve.MIN_OVERDRAW, "min_layers": occlusion.MIN_LAYERS}
    for width, height in SIZES:
        facts[f"layers_{width}x{height}"] = mesh_data.layers_over_view(baked.origins, baked.box_half_extents, to_clip,
                                                                        width, height)
    return facts


def preview_arrays(baked, settings, to_clip, to_view) -> dict:
    """What the preview uploads to draw a baked object (CLASSIC layout) and what draw_object
    decides for it (preview_facts), with the shader sources."""
    from boxmarch.preview import draw, mesh_data

    inputs = mesh_data.layout_inputs("CLASSIC", baked)
    octant = mesh_data.view_octant(to_view)
    arrays = {f"input_{k}": np.ascontiguousarray(v, np.float32) for k, v in inputs.items()}
    arrays["input_names"] = np.array(list(inputs))
    arrays["triangles_file"] = baked.triangles.astype(np.uint32)
    arrays["triangles_octant"] = mesh_data.octant_triangles(baked, octant).astype(np.uint32)
    arrays["uniform_block"] = draw.uniform_block_data(to_clip, to_view, True, settings, 0, BASE_COLOR, None,
                                                      REFERENCE_SIZE[1])
    arrays["object_to_clip"], arrays["object_to_view"] = to_clip, to_view
    arrays.update({f"source_{k}": np.array(v) for k, v in stage_sources(settings.sdf).items()})
    arrays.update(preview_facts(baked, settings, to_clip, to_view))
    return arrays


def scene_arrays(bpy, name, scene) -> dict:
    from bench.bench_preview_cost import baked_object
    from boxmarch import core
    from boxmarch.preview import mesh_data

    ob = baked_object(bpy, name, scene)
    settings = ob.boxmarch
    to_clip, to_view = widescreen(scene[4])
    baked = mesh_data.read_baked(ob.data)
    arrays = preview_arrays(baked, settings, to_clip, to_view)
    arrays["march"] = np.array([settings.epsilon, settings.relaxation, settings.max_distance, settings.max_steps])
    boxes = np.zeros((len(baked.origins), 3, 4), np.float32)  # the naive shader's texture
    boxes[:, 0, :3], boxes[:, 1], boxes[:, 2, :3] = baked.origins, baked.box_quaternions, baked.box_half_extents
    arrays["naive_boxes"] = boxes
    for quality in QUALITIES:
        reference = core.render_boxes(baked.origins, baked.box_quaternions, baked.box_half_extents, to_clip, to_view,
                                      *REFERENCE_SIZE, base_color=BASE_COLOR[:3], sdf=settings.sdf,
                                      max_steps=settings.max_steps, epsilon=settings.epsilon,
                                      relaxation=settings.relaxation, max_distance=settings.max_distance,
                                      quality=quality)
        arrays[f"reference_depth_{quality}"] = reference.depth
        if quality == 1.0:
            arrays["reference_rgba8"] = np.rint(np.clip(reference.rgba, 0, 1) * 255).astype(np.uint8)
    arrays["info"] = np.array([name, settings.sdf, str(len(baked.origins)), str(mesh_data.view_octant(to_view))])
    bpy.data.objects.remove(ob)
    return arrays


def chain_arrays(bpy, count) -> dict:
    """bench_boxes_vs_triangles.chain_rows(count) baked and stored compactly (chain_data.py), with
    its links' origins and rotations (the triangle mesh is made from them where it is drawn) and
    the CLASSIC export's vertex bytes."""
    from bench import chain_data
    from bench.bench_boxes_vs_triangles import chain_rows, layout_bytes
    from bench.bench_preview_cost import baked_object
    from boxmarch.preview import mesh_data

    scene = chain_rows(count)
    ob = baked_object(bpy, f"chain {count}", scene)
    baked = mesh_data.read_baked(ob.data)
    to_clip, to_view, _eye = scene[4]
    arrays = preview_arrays(baked, ob.boxmarch, to_clip, to_view)
    vertices_per_box = len(baked.positions) // count
    stored = chain_data.compact(arrays, 2, vertices_per_box)
    stored.update({k: v for k, v in arrays.items() if not k.startswith(("input_", "triangles_"))})
    stored.update(origins=scene[0].astype(np.float32), rotations=scene[1].astype(np.float32),
                  classic_vertex_bytes=np.int64(layout_bytes()["CLASSIC"] * len(baked.positions)))
    bpy.data.objects.remove(ob)
    return stored


def main():
    import argparse

    import bpy

    import boxmarch
    from bench.bench_gpu_cost import scenes_to_measure, smaller_piles

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--chains", default="1000,10000,100000",
                        help="chain lengths of bench_gpu_triangles.py, written into OUT/chains (empty: none)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    made = {**scenes_to_measure(480, 8), **smaller_piles(480)}
    written = [(args.out / (name.replace(" ", "_") + ".npz"), lambda name=name: scene_arrays(bpy, name, made[name]))
               for name in SCENES]
    written += [(args.out / "chains" / f"chain_{count}.npz", lambda count=count: chain_arrays(bpy, count))
                for count in (int(c) for c in args.chains.split(",") if c)]
    for path, arrays in written:
        path.parent.mkdir(exist_ok=True)
        np.savez_compressed(path, **arrays())
        print(f"{path}: {path.stat().st_size / 2**20:.1f} MiB")
    sys.stdout.flush()
    import os
    os._exit(0)  # bpy modules with registered add-ons may crash at exit (docs: shared notes)


if __name__ == "__main__":
    main()

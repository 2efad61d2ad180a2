"""Viewport preview benchmark: the boxed raymarch against a naive full-screen raymarch.

Scene: 16,000 random boxes (scenes.random_boxes, seed 0: sizes 0.05-2, in a cube of side 200),
baked, previewed with the SPHERE preset; a camera inside the cloud; 960 x 540; Mesa llvmpipe.

* boxed: the preview's one draw call (preview/draw.py) into an offscreen buffer, timed from
  clear to a 1-pixel read-back (which waits for the GPU); best of several frames. Steps per pixel
  from the preview's STEPS output (SDF evaluations summed over every fragment of the pixel).
* naive: the usual full-screen "one big SDF": every pixel marches from the camera, every step
  evaluates all 16,000 spheres (bench/naive_fullscreen.frag.glsl, the same SDF library). It is
  far too slow for the full frame on llvmpipe, so it renders a centred 96 x 54 tile of the SAME
  camera view (1 % of the pixels) and its frame time is that x (960 x 540) / (96 x 54): every
  pixel of this shader is independent work, so time scales with the pixel count.
* CPU reference: boxmarch.core.render_boxes of the same frame (C++, all cores), for scale.
* skinned: the same boxes rigged to a chain of 8 bones along x (each box rigidly weighted to the
  bone over it), NORMAL_FRAME layout, an Armature modifier: a redraw after a pose change is the
  preview's CPU update (evaluated positions read, normals and tangents skinned, vertex buffer
  uploaded) plus the draw; a redraw without one is the draw alone. Blender's own evaluation of the
  modifier (the depsgraph update a pose change causes) is timed apart, for scale.

    python3 -m bench.bench_preview [--boxes N] [--repeats R]

Runs itself inside Debian's Blender program (the GPU module needs it headless).
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
WIDTH, HEIGHT = 960, 540
TILE = (96, 54)


def in_blender(args):
    import bpy
    import gpu
    import numpy as np
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix

    import boxmarch
    from bench.common import best_of, boxes_object, preview_frame
    from boxmarch import core, preview
    from boxmarch.formats import shader_sources
    from boxmarch.preview import draw, mesh_data

    boxmarch.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    preview.ensure_gpu_context()
    ob, _centres, _sizes = boxes_object(bpy, args["boxes"])
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    ob.boxmarch.preview = True
    ob.boxmarch.sdf = "SPHERE"
    settings = ob.boxmarch
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = (0.0, -60.0, 10.0)
    camera.rotation_euler = (1.45, 0.0, 0.0)
    camera.data.clip_start, camera.data.clip_end = 0.1, 400.0
    scene.camera = camera
    bpy.context.view_layer.update()
    view, projection = preview.camera_matrices(scene, camera, WIDTH, HEIGHT)
    model = np.array(ob.matrix_world)

    # boxed: the preview's own draw, one call
    offscreen = gpu.types.GPUOffScreen(WIDTH, HEIGHT, format="RGBA32F")
    draw.draw_object(ob, view, projection, True)  # builds and caches the batch outside the timing

    def boxed_frame():
        preview_frame(offscreen, ob, view, projection)

    boxed = best_of(args["repeats"], boxed_frame)
    steps_rgba, _ = preview.render(scene, camera, WIDTH, HEIGHT, output="STEPS")
    rgba, depth = preview.render(scene, camera, WIDTH, HEIGHT)
    boxed_steps = steps_rgba[..., 0]
    coverage = float((depth < 1.0).mean())

    # naive full-screen raymarch of the same spheres, on a centred tile of the same view
    baked = mesh_data.read_baked(ob.data)
    box_count = len(baked.origins)
    texels = np.zeros((box_count, 3, 4), np.float32)
    texels[:, 0, :3] = baked.origins
    texels[:, 1] = baked.box_quaternions
    texels[:, 2, :3] = baked.box_half_extents
    texture = gpu.types.GPUTexture((3, box_count), format="RGBA32F",
                                   data=gpu.types.Buffer("FLOAT", texels.size, texels.ravel().tolist()))
    info = gpu.types.GPUShaderCreateInfo()
    info.vertex_in(0, "VEC2", "pos")
    info.push_constant("MAT4", "clip_to_object")
    info.push_constant("VEC4", "march")
    info.push_constant("IVEC4", "sizes")
    info.sampler(0, "FLOAT_2D", "boxes")
    info.fragment_out(0, "VEC4", "frag_color")
    info.vertex_source("void main() { gl_Position = vec4(pos, 0.0, 1.0); }")
    info.fragment_source("\n".join([shader_sources.read_glsl("decode.glsl"), shader_sources.read_glsl("sdf.glsl"),
                                    (HERE / "naive_fullscreen.frag.glsl").read_text()]))
    naive_shader = gpu.shader.create_from_info(info)
    triangle = batch_for_shader(naive_shader, "TRIS", {"pos": [(-1.0, -1.0), (3.0, -1.0), (-1.0, 3.0)]})
    # the tile's own projection: the centre 96 x 54 pixels of the full view
    tw, th = TILE
    crop = np.diag([WIDTH / tw, HEIGHT / th, 1.0, 1.0])
    tile_clip = crop @ projection @ view @ model
    tile = gpu.types.GPUOffScreen(tw, th, format="RGBA32F")

    def naive_frame(read=False):
        with tile.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            naive_shader.bind()
            naive_shader.uniform_float("clip_to_object", Matrix(np.linalg.inv(tile_clip).tolist()))
            naive_shader.uniform_float("march", (settings.epsilon, settings.relaxation, settings.max_distance,
                                                 settings.max_steps))
            naive_shader.uniform_int("sizes", (box_count, tw, th, 0))
            naive_shader.uniform_sampler("boxes", texture)
            triangle.draw(naive_shader)
            buffer = fb.read_color(0, 0, tw if read else 1, th if read else 1, 4, 0, "FLOAT")
        if read:
            buffer.dimensions = tw * th * 4
            return np.array(buffer, np.float32).reshape(th, tw, 4)[::-1]

    naive_tile = best_of(max(1, args["repeats"] // 2), naive_frame)
    naive_image = naive_frame(read=True)
    y0, x0 = (HEIGHT - th) // 2, (WIDTH - tw) // 2
    boxed_tile_hit = depth[y0:y0 + th, x0:x0 + tw] < 1.0
    agreement = float((boxed_tile_hit == (naive_image[..., 0] > 0.5)).mean())

    # CPU reference of the full frame
    cpu = best_of(1, lambda: core.render_boxes(baked.origins, baked.box_quaternions, baked.box_half_extents,
                                               projection @ view @ model, view @ model, WIDTH, HEIGHT,
                                               sdf="SPHERE", max_steps=settings.max_steps, epsilon=settings.epsilon))
    reference = core.render_boxes(baked.origins, baked.box_quaternions, baked.box_half_extents,
                                  projection @ view @ model, view @ model, WIDTH, HEIGHT, sdf="SPHERE",
                                  max_steps=settings.max_steps, epsilon=settings.epsilon)
    return {
        "boxes": box_count, "coverage": coverage, "boxed_ms": boxed * 1e3,
        "boxed_steps_per_pixel": float(boxed_steps.mean()),
        "boxed_steps_per_covered_pixel": float(boxed_steps[depth < 1.0].mean()) if coverage else 0.0,
        "naive_tile_ms": naive_tile * 1e3, "naive_ms": naive_tile * 1e3 * (WIDTH * HEIGHT) / (tw * th),
        "naive_steps_per_pixel": float(naive_image[..., 1].mean()),
        "naive_tile_agreement": agreement,
        "cpu_ms": cpu * 1e3, "cpu_steps_per_pixel": float(reference.steps.mean()),
        "cpu_gpu_coverage_agreement": float(((reference.depth < 1.0) == (depth < 1.0)).mean()),
        "renderer": gpu.platform.renderer_get(),
        **skinned(bpy, ob, view, projection, boxed_frame, args["repeats"]),
    }


BONES, BONE_TURN = 8, 0.03  # the bench rig: a chain along x; each pose turns every joint this much (radians)


def skinned(bpy, ob, view, projection, boxed_frame, repeats):
    """Redraw costs of the boxes rigged to a chain and posed (see the docstring)."""
    import time

    import numpy as np
    from mathutils import Quaternion

    from bench.common import best_of
    from boxmarch import mesh_io
    from boxmarch.preview import draw, skinning

    scene = bpy.context.scene
    ob.boxmarch.sdf = "SPHERE"
    ob.boxmarch.layout = "NORMAL_FRAME"
    draw.draw_object(ob, view, projection, True)  # the unposed buffers, outside the timing
    unposed = best_of(repeats, boxed_frame)

    rig = bpy.data.objects.new("rig", bpy.data.armatures.new("rig"))
    scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    parent, length = None, 200.0 / BONES
    for k in range(BONES):
        bone = rig.data.edit_bones.new(f"bone{k}")
        bone.head, bone.tail = (-100.0 + k * length, 0.0, 0.0), (-100.0 + (k + 1) * length, 0.0, 0.0)
        if parent is not None:
            bone.parent, bone.use_connect = parent, True
        parent = bone
    bpy.ops.object.mode_set(mode="OBJECT")
    positions = mesh_io.read_positions(ob.data)
    box_x = positions.reshape(-1, 8, 3)[:, :, 0].mean(axis=1)
    bone_of_box = np.clip(((box_x + 100.0) // length).astype(int), 0, BONES - 1)
    bone_of_vertex = np.repeat(bone_of_box, 8)
    for k in range(BONES):
        ob.vertex_groups.new(name=f"bone{k}").add(np.flatnonzero(bone_of_vertex == k).tolist(), 1.0, "REPLACE")
    ob.modifiers.new("Armature", "ARMATURE").object = rig
    bpy.context.view_layer.update()

    start = time.perf_counter()
    draw.draw_object(ob, view, projection, True)  # weights read once, first posed buffers
    first = time.perf_counter() - start
    turn = [0]

    def pose():
        turn[0] += 1
        for pose_bone in rig.pose.bones:
            pose_bone.rotation_mode = "QUATERNION"
            pose_bone.rotation_quaternion = Quaternion((0.0, 0.0, 1.0), BONE_TURN * (1 if turn[0] % 2 else -1))
        bpy.context.view_layer.update()

    evaluation = best_of(repeats, pose)
    depsgraph = bpy.context.evaluated_depsgraph_get()

    def update():
        draw.pose_changed(ob.name_full)
        draw.drawing(ob, depsgraph)

    pose_update = best_of(repeats, update)
    modifier = skinning.armature_modifier(ob)
    weights = draw.posed_state(ob.name_full).weights
    frames_only = best_of(repeats, lambda: skinning.skin_linear(weights, skinning.bone_deformations(
        ob, modifier, weights.bones, depsgraph)))
    positions_only = best_of(repeats, lambda: skinning.evaluated_positions(ob, depsgraph, len(positions)))
    posed_draw = best_of(repeats, boxed_frame)
    assert not draw.errors.get(ob.name), draw.errors.get(ob.name)
    return {"skinned_vertices": len(positions), "bones": BONES, "unposed_draw_ms": unposed * 1e3,
            "first_posed_draw_ms": first * 1e3, "blender_pose_evaluation_ms": evaluation * 1e3,
            "pose_update_ms": pose_update * 1e3, "skin_matrices_ms": frames_only * 1e3,
            "evaluated_positions_ms": positions_only * 1e3, "posed_draw_ms": posed_draw * 1e3}


def report(r):
    from bench.common import table

    evaluations_naive = r["naive_steps_per_pixel"] * r["boxes"]

    def relative(ms):
        ratio = ms / r["boxed_ms"]
        return f"{ratio:.{0 if ratio >= 10 else 1}f}x slower" if ratio >= 1 else f"{1 / ratio:.1f}x faster"

    rows = [
        ("boxed (preview, 1 draw call)", f"{r['boxed_ms']:.1f}", f"{r['boxed_steps_per_pixel']:.2f}",
         f"{r['boxed_steps_per_pixel']:.2f}", "1.0x"),
        ("naive full-screen, all boxes per step", f"{r['naive_ms']:.0f}", f"{r['naive_steps_per_pixel']:.1f}",
         f"{evaluations_naive:.0f}", relative(r["naive_ms"])),
        ("CPU reference (C++, boxed)", f"{r['cpu_ms']:.0f}", f"{r['cpu_steps_per_pixel']:.2f}",
         f"{r['cpu_steps_per_pixel']:.2f}", relative(r["cpu_ms"])),
    ]
    print(f"{r['boxes']} boxes, {WIDTH} x {HEIGHT}, SPHERE preset, {r['renderer']}; "
          f"{100 * r['coverage']:.1f} % of pixels covered")
    print(table(["method", "frame ms", "march steps / pixel", "box SDF evaluations / pixel", "vs boxed"], rows))
    print(f"naive: {TILE[0]} x {TILE[1]} centre tile took {r['naive_tile_ms']:.0f} ms (scaled to the frame); "
          f"its coverage agrees with the boxed preview on {100 * r['naive_tile_agreement']:.2f} % of the tile")
    print(f"boxed: {r['boxed_steps_per_covered_pixel']:.2f} steps per covered pixel; CPU reference and GPU "
          f"coverage agree on {100 * r['cpu_gpu_coverage_agreement']:.3f} % of pixels")
    print()
    print(f"Skinned: the same {r['boxes']} boxes ({r['skinned_vertices']} vertices) on a {r['bones']}-bone chain, "
          f"NORMAL_FRAME layout, SPHERE preset")
    rows = [
        ("unposed (no Armature modifier)", "-", f"{r['unposed_draw_ms']:.1f}", f"{r['unposed_draw_ms']:.1f}"),
        ("posed, pose unchanged (e.g. the view orbits)", "-", f"{r['posed_draw_ms']:.1f}", f"{r['posed_draw_ms']:.1f}"),
        ("posed, after a pose change", f"{r['pose_update_ms']:.1f}", f"{r['posed_draw_ms']:.1f}",
         f"{r['pose_update_ms'] + r['posed_draw_ms']:.1f}"),
    ]
    print(table(["redraw", "pose update ms (CPU)", "draw ms", "redraw ms"], rows))
    print(f"pose update = evaluated positions read {r['evaluated_positions_ms']:.1f} ms + skinning matrices "
          f"{r['skin_matrices_ms']:.1f} ms + normals/tangents and vertex buffer upload; Blender's own Armature "
          f"modifier evaluation per pose change {r['blender_pose_evaluation_ms']:.1f} ms; first posed draw (weights "
          f"read once) {r['first_posed_draw_ms']:.0f} ms")


def main():
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--boxes", type=int, default=16000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    blender = shutil.which("blender")
    if blender is None:
        sys.exit("Debian's blender is missing: run scripts/setup.sh")
    import boxmarch

    with tempfile.TemporaryDirectory() as tmp:
        parent = Path(tmp) / "path"
        parent.mkdir()
        (parent / "boxmarch").symlink_to(Path(boxmarch.__file__).parent, target_is_directory=True)
        out = Path(tmp) / "result.json"
        env = dict(os.environ, HOME=tmp, TMPDIR=tmp, XDG_CACHE_HOME=tmp, XDG_CONFIG_HOME=tmp)
        env.pop("PYTHONPATH", None)
        env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
        proc = subprocess.run([blender, "--background", "--factory-startup", "--python-exit-code", "1", "--python",
                               __file__, "--", str(parent), str(out), json.dumps(vars(args), allow_nan=False)],
                              env=env, capture_output=True, text=True)
        if proc.returncode != 0 or not out.exists():
            sys.exit(proc.stdout[-4000:] + proc.stderr[-4000:])
        report(json.loads(out.read_text()))


if __name__ == "__main__":
    if "--" in sys.argv:  # inside Blender
        parent, out, options = sys.argv[sys.argv.index("--") + 1:]
        sys.path[:0] = [parent, str(HERE.parent)]  # Blender runs this file by path
        Path(out).write_text(json.dumps(in_blender(json.loads(options)), allow_nan=False))
    else:
        main()

"""Run in a Blender (Debian's 3.4 program in the background, or the bpy module): a dense pile of
links drawn by the viewport preview offscreen with and without the hidden-box pre-pass
(preview/occlusion.py), and with its resolved passes (preview/resolve.py): the shaded images
and the STEPS output (green: SDF evaluations of every fragment, summed per pixel through an
additive float target), with the pile's ground truth.

Usage: blender --background --factory-startup --python preview_occluder_check.py -- PACKAGE_PARENT OUT.npz
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402
from boxmarch.formats import shader_sources  # noqa: E402
from boxmarch.preview import draw, occlusion, resolve  # noqa: E402
from boxmarch.preview import shader as pv_shader  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 200, 150
LINK = np.array([0.46, 0.23, 0.06])  # scripts/chain_arm.py's link: length, width, wire thickness

# 600 links heaped at random in a 1.6-unit cube, seen through from 3.5 units away.
rng = np.random.default_rng(5)
centres = rng.uniform(-0.8, 0.8, (600, 3))
rotations = scenes.random_rotations(600, rng)
positions, _edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(centres, np.tile(LINK, (600, 1)),
                                                                              rotations)
pile = bpy.data.objects.new("pile", mesh_io.new_mesh("pile", positions, face_starts, face_sizes, corner_verts))
scene.collection.objects.link(pile)
bpy.context.view_layer.objects.active = pile
pile.select_set(True)
assert bpy.ops.boxmarch.bake(sort_axes_by_extent=True) == {"FINISHED"}  # local x along each link
pile.boxmarch.preview = True
pile.boxmarch.sdf = "LINK"

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = (0.4, -3.5, 0.6)
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start, camera.data.clip_end = 0.1, 100.0
scene.camera = camera
bpy.context.view_layer.update()

result = {"centres": centres, "rotations": rotations, "link": LINK, "matrix_world": np.array(pile.matrix_world)}
result["view"], result["projection"] = preview.camera_matrices(scene, camera, W, H)
# ON: the pre-pass with the one-pass march; RESOLVED: with the resolved passes (preview/resolve.py,
# forced whatever the overdraw; Blender 4.2 and later); BROKEN: the resolved passes with the shade
# pass given the visibility pass's word (a negative control: it must not draw the picture).
configs = {"ON": (True, False, resolve.SHADE), "OFF": (False, False, resolve.SHADE)}
result["resolved_available"] = resolve.available()
if resolve.available():
    configs.update(RESOLVED=(True, True, resolve.SHADE), BROKEN=(True, True, resolve.VISIBILITY))
shade, minimum, min_layers = resolve.SHADE, resolve.MIN_OVERDRAW, occlusion.MIN_LAYERS
occlusion.MIN_LAYERS = 0.0  # the pre-pass whatever the depth of the boxes (but in BELOW_MIN_LAYERS)
for name, (enabled, resolved, shade_word) in configs.items():
    occlusion.ENABLED, resolve.ENABLED, resolve.SHADE = enabled, resolved, shade_word
    resolve.MIN_OVERDRAW = 0.0
    result[f"{name}_rgba"], result[f"{name}_depth"] = preview.render(scene, camera, W, H)
    result[f"{name}_steps"] = preview.render(scene, camera, W, H, output="STEPS")[0]
resolve.SHADE = shade
# Boxes fewer layers deep than occlusion.MIN_LAYERS: no pre-pass (the same counts as OFF).
occlusion.ENABLED, resolve.ENABLED, occlusion.MIN_LAYERS = True, True, float("inf")
result["BELOW_MIN_LAYERS_steps"] = preview.render(scene, camera, W, H, output="STEPS")[0]
occlusion.MIN_LAYERS = 0.0
# Below full quality (the pile from 20 times as far: its links under 2 px long, under the knob's
# one-tap size at 0.5 and 0.25): the link's closed form takes no one-tap, so its pre-pass stays
# (occlusion.occluder_count's gate stops it for marched shapes only): the picture is the one
# without it, and the pre-pass's draws are counted (at full quality too). The picture alone cannot show the gate here: far off, the
# links' occluders are thinner than the pre-pass's rounding margins and draw nothing.
camera.location = 20.0 * Vector((0.4, -3.5, 0.6))
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
draw_occluders, pre_passes = occlusion.draw_occluders, []


def counted_draw_occluders(*args, **kwargs):
    pre_passes.append(1)
    return draw_occluders(*args, **kwargs)


occlusion.draw_occluders = counted_draw_occluders
for quality in (0.5, 0.25, 1.0):
    pile.boxmarch.quality = quality
    for name, enabled in (("ON", True), ("OFF", False)):
        occlusion.ENABLED, resolve.ENABLED = enabled, False
        pre_passes.clear()
        result[f"Q{quality}_{name}_rgba"] = preview.render(scene, camera, W, H)[0]
        result[f"Q{quality}_{name}_pre_passes"] = np.array(len(pre_passes))
occlusion.draw_occluders = draw_occluders
pile.boxmarch.quality = 1.0
# the marched shape (PER_BOX_BLEND: each box's shape blended with its parent's) below full quality
occlusion.ENABLED = True
for quality in (0.5, 0.25, 1.0):
    result[f"Q{quality}_PER_BOX_BLEND_count"] = np.array(occlusion.occluder_count("PER_BOX_BLEND", quality))
camera.location = (0.4, -3.5, 0.6)
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
# The hard cases: the eye inside a box of the pile (that box marches from the eye; boxes the near
# plane cuts lie around it) and the pile mirrored (front faces culled), without the pre-pass, with
# it and one pass, and in the resolved passes (there the boxes holding the eye draw with the depth
# test off).
pile.scale = (-1.0, 1.0, 1.0)
bpy.context.view_layer.update()  # the mirrored matrix_world
camera.location = pile.matrix_world @ Vector(centres[0])
camera.rotation_euler = (Vector((0.0, 0.0, 0.0)) - camera.location).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
inside = {"INSIDE_OFF": (False, False), "INSIDE_ONE_PASS": (True, False)}
if resolve.available():
    inside["INSIDE_RESOLVED"] = (True, True)
for name, (enabled, resolved) in inside.items():
    occlusion.ENABLED, resolve.ENABLED = enabled, resolved
    result[f"{name}_rgba"], result[f"{name}_depth"] = preview.render(scene, camera, W, H)
# A GPU backend where a shader of the resolved passes does not compile: the preview says so once
# and marches in one pass (the full-screen stage's source broken for the test).
if resolve.available():
    occlusion.ENABLED, resolve.ENABLED = True, True
    fullscreen_source = shader_sources.fullscreen_source
    shader_sources.fullscreen_source = lambda stage: fullscreen_source(stage) + "\nnot glsl"
    pv_shader.clear_cache()
    result["FALLBACK_rgba"], result["FALLBACK_depth"] = preview.render(scene, camera, W, H)
    result["fallback_refused"] = resolve.refused or ""
    shader_sources.fullscreen_source = fullscreen_source
    resolve.refused = None
    pv_shader.clear_cache()
# The eye inside a large box of a mirrored object (a room: a torus's box, the eye in the torus's
# hole looking at its far wall over the tube), with 20 small tori inside the tube: the room's far
# faces, front-facing on screen in the mirrored object, are the fragments that march from the eye.
# Without the cut (no culling, no pre-pass) and by default (culling, the pre-pass whatever the depth).
pile.hide_viewport = pile.hide_render = True
pile.boxmarch.preview = False
room_rng = np.random.default_rng(3)
room_centres = np.vstack([[0.0, 0.0, 0.0], np.c_[room_rng.uniform(1.9, 2.7, 20), room_rng.uniform(-1.2, 1.2, 20),
                                                 room_rng.uniform(-0.4, 0.4, 20)]])
room_sizes = np.vstack([[6.0, 6.0, 1.6], np.tile([0.3, 0.3, 0.1], (20, 1))])
room_rotations = np.vstack([np.eye(3)[None], scenes.random_rotations(20, room_rng)])
arrays = scenes.box_arrays(room_centres, room_sizes, room_rotations)
room = bpy.data.objects.new("room", mesh_io.new_mesh("room", arrays[0], *arrays[2:]))
scene.collection.objects.link(room)
for other in scene.objects:
    other.select_set(other == room)
bpy.context.view_layer.objects.active = room
assert bpy.ops.boxmarch.bake(sort_axes_by_extent=False) == {"FINISHED"}
room.boxmarch.preview = True
room.boxmarch.sdf = "TORUS"
room.scale = (-1.0, 1.0, 1.0)
camera.location = room.matrix_world @ Vector((0.3, 0.2, 0.1))
camera.rotation_euler = (room.matrix_world.to_3x3() @ Vector((1.0, 0.1, 0.6))).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
result.update(room_centres=room_centres, room_half=room_sizes / 2, room_rotations=room_rotations,
              room_matrix_world=np.array(room.matrix_world))
result["room_view"], result["room_projection"] = preview.camera_matrices(scene, camera, W, H)
for name, enabled in (("ROOM_PLAIN", False), ("ROOM_DEFAULT", True)):
    occlusion.ENABLED, resolve.ENABLED, draw.CULL_BACK_FACES = enabled, False, enabled
    result[f"{name}_rgba"], result[f"{name}_depth"] = preview.render(scene, camera, W, H)
# Looking at the small tori (their occluders in front of the room's far faces over much of the
# view): the SDF evaluations of every fragment with the pre-pass, where the room's marches from the
# eye run bounded by the occluders, never dropped (STEPS, green).
camera.rotation_euler = (room.matrix_world.to_3x3() @ Vector((1.0, 0.0, -0.05))).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
result["room_low_view"], result["room_low_projection"] = preview.camera_matrices(scene, camera, W, H)
occlusion.ENABLED, resolve.ENABLED, draw.CULL_BACK_FACES = True, False, True
result["ROOM_LOW_steps"] = preview.render(scene, camera, W, H, output="STEPS")[0]
occlusion.ENABLED, resolve.ENABLED, resolve.SHADE, resolve.MIN_OVERDRAW = True, True, shade, minimum
occlusion.MIN_LAYERS, draw.CULL_BACK_FACES = min_layers, True

np.savez_compressed(out_path, **result)
sys.stdout.flush()
os._exit(0)  # PyPI's bpy 4.2/4.5 crash at exit once an add-on registered classes (docs/PLATFORMS.md)

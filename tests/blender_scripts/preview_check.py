"""Run inside Debian's Blender (background): bakes a box scene, renders it through the viewport
preview offscreen (GPU, llvmpipe here) and writes the images with the scene's ground truth.

Usage: blender --background --factory-startup --python preview_check.py -- PACKAGE_PARENT OUT.npz
"""
import os
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, argv[0])
out_path = argv[1]

import bpy  # noqa: E402
import mathutils  # noqa: E402
import numpy as np  # noqa: E402

import boxmarch  # noqa: E402
from boxmarch.formats import layouts  # noqa: E402
from boxmarch import mesh_io, preview, scenes  # noqa: E402
from boxmarch.preview import draw, mesh_data  # noqa: E402

boxmarch.register()
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
W, H = 320, 240

# 24 randomly turned boxes, some overlapping, seen by a perspective camera.
(positions, _edges, face_starts, face_sizes, corner_verts), centres, sizes, rotations = \
    scenes.random_boxes(24, seed=7, spread=2.5, size_range=(0.4, 1.6))
mesh = mesh_io.new_mesh("boxes", positions, face_starts, face_sizes, corner_verts)
boxes = bpy.data.objects.new("boxes", mesh)
scene.collection.objects.link(boxes)
boxes.location = (0.3, -0.2, 0.1)
boxes.rotation_euler = (0.2, 0.1, 0.4)
boxes.scale = (1.15, 0.85, 1.0)  # non-uniform: rays and normals must go through the right matrices
bpy.context.view_layer.objects.active = boxes
boxes.select_set(True)
# Per-box shape ids: box i (vertices 8i..8i+7) draws preset SHAPES[i] in the PER_BOX renders.
shapes = (np.arange(24) * 5 + 1) % 7
mesh.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set("value", np.repeat(shapes, 8).astype(np.int32))
assert bpy.ops.boxmarch.bake() == {"FINISHED"}

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = (7.5, -8.0, 6.0)
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start, camera.data.clip_end = 0.5, 40.0
scene.camera = camera
bpy.context.view_layer.update()

result = {"centres": centres, "sizes": sizes, "rotations": rotations, "shapes": shapes,
          "matrix_world": np.array(boxes.matrix_world), "color": np.array(boxes.color)}
view, projection = preview.camera_matrices(scene, camera, W, H)
result["view"], result["projection"] = view, projection

# The baked layers as Blender stores them, for the reference of the asymmetric presets.
corner_verts = np.empty(len(mesh.loops), np.int32)
mesh.loops.foreach_get("vertex_index", corner_verts)
offsets = np.empty(len(mesh.vertices) * 4, np.float32)
mesh.color_attributes["BoxOffset"].data.foreach_get("color", offsets)
corner_q = []
for name in ("BoxQuatXY", "BoxQuatZW"):
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers[name].data.foreach_get("uv", uv)
    corner_q.append(uv.reshape(-1, 2))
result.update(layer_positions=mesh_io.read_positions(mesh), layer_offsets=offsets.reshape(-1, 4),
              layer_corner_verts=corner_verts, layer_corner_quaternions=np.concatenate(corner_q, axis=1))

boxes.boxmarch.preview = True
for sdf in ("BOX", "SPHERE", "ROUNDED_BOX", "CAPSULE", "CYLINDER", "TORUS", "LINK"):
    boxes.boxmarch.sdf = sdf
    for output in ("SHADED", "NORMAL"):
        rgba, depth = preview.render(scene, camera, W, H, output=output)
        result[f"{sdf}_{output}_rgba"], result[f"{sdf}_{output}_depth"] = rgba, depth

# Every engine layout, drawn from its own channels and decoded by the shipped decode functions;
# then, as a negative control, each with its frame channels replaced by the identity frame.
boxes.boxmarch.sdf = "ROUNDED_BOX"
for layout in layouts.LAYOUTS:
    boxes.boxmarch.layout = layout
    result[f"LAYOUT_{layout}_rgba"], result[f"LAYOUT_{layout}_depth"] = preview.render(scene, camera, W, H)
layout_inputs = mesh_data.layout_inputs


def unturned_inputs(layout, baked):
    inputs = layout_inputs(layout, baked)
    n = len(baked.positions)
    if "ch_normal" in inputs:
        inputs["ch_normal"] = np.tile(np.float32([0.0, 0.0, 1.0]), (n, 1))
        inputs["ch_tangent"] = np.tile(np.float32([1.0, 0.0, 0.0, 1.0]), (n, 1))
    else:
        inputs["ch_uv1"] = np.zeros((n, 2), np.float32)
        inputs["ch_uv2"] = np.tile(np.float32([0.0, 1.0]), (n, 1))
    return inputs


mesh_data.layout_inputs = unturned_inputs
draw.forget()
for layout in layouts.LAYOUTS:
    boxes.boxmarch.layout = layout
    result[f"UNTURNED_{layout}_rgba"], result[f"UNTURNED_{layout}_depth"] = preview.render(scene, camera, W, H)
mesh_data.layout_inputs = layout_inputs
draw.forget()

# Each box the preset its shape id picks, read from every layout's channels or box table.
boxes.boxmarch.sdf = "PER_BOX"
for layout in layouts.LAYOUTS:
    boxes.boxmarch.layout = layout
    result[f"PER_BOX_{layout}_rgba"], result[f"PER_BOX_{layout}_depth"] = preview.render(scene, camera, W, H)
boxes.boxmarch.layout = "CLASSIC"

# A user SDF: the same sphere written by hand must give the SPHERE preset's image.
text = bpy.data.texts.new("my_sphere.glsl")
text.write("float map(vec3 p)\n{\n  return sd_sphere(p, min3(box_half));\n}\n")
boxes.boxmarch.sdf = "USER"
boxes.boxmarch.user_text = text.name
result["USER_SHADED_rgba"], result["USER_SHADED_depth"] = preview.render(scene, camera, W, H)
result["user_error"] = str(draw.errors.get(boxes.name))

# A broken user SDF: the error names the line, and only the outline is drawn.
broken = bpy.data.texts.new("broken.glsl")
broken.write("float map(vec3 p)\n{\n  float r = min3(box_half);\n  return lenght(p) - r;\n}\n")
boxes.boxmarch.user_text = broken.name
result["BROKEN_rgba"], result["BROKEN_depth"] = preview.render(scene, camera, W, H)
result["broken_error"] = str(draw.errors.get(boxes.name))

# Composition by depth with an ordinary mesh: a ground plane cutting through the spheres.
boxes.boxmarch.sdf = "SPHERE"
bpy.ops.mesh.primitive_plane_add(size=12.0, location=(0.0, 0.0, 0.2))
plane = bpy.context.active_object
result["COMPOSITE_rgba"], result["COMPOSITE_depth"] = preview.render(scene, camera, W, H)
boxes.hide_viewport = True
result["PLANE_rgba"], result["PLANE_depth"] = preview.render(scene, camera, W, H)
result["plane_matrix"] = np.array(plane.matrix_world)

# The plane away again, the boxes back.
plane.hide_viewport = True
boxes.hide_viewport = False

# Baked data expressed in another object frame (as an export preset may write it): quaternions
# turned by F; with F given as the object's frame the preview must draw the same tori.
boxes.boxmarch.sdf = "TORUS"
result["TORUS_rgba"], result["TORUS_depth"] = preview.render(scene, camera, W, H)
F = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # a proper rotation
F_quat = np.array(mathutils.Matrix(F.tolist()).to_quaternion())  # w, x, y, z
uv = {}
for name in ("BoxQuatXY", "BoxQuatZW"):
    uv[name] = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers[name].data.foreach_get("uv", uv[name])
q = np.concatenate([uv["BoxQuatXY"].reshape(-1, 2), uv["BoxQuatZW"].reshape(-1, 2)], axis=1).astype(np.float64)
fw, fv = F_quat[0], F_quat[1:]
turned = np.empty_like(q)  # Hamilton product F_quat * q, (x, y, z, w) layout
turned[:, 3] = fw * q[:, 3] - q[:, :3] @ fv
turned[:, :3] = fw * q[:, :3] + q[:, 3:4] * fv + np.cross(fv, q[:, :3])
mesh.uv_layers["BoxQuatXY"].data.foreach_set("uv", turned[:, :2].astype(np.float32).ravel())
mesh.uv_layers["BoxQuatZW"].data.foreach_set("uv", turned[:, 2:].astype(np.float32).ravel())
mesh.update()
bpy.context.view_layer.update()
result["TORUS_TURNED_rgba"], result["TORUS_TURNED_depth"] = preview.render(scene, camera, W, H)
boxes["boxmarch_frame"] = F.ravel().tolist()
result["TORUS_FRAMED_rgba"], result["TORUS_FRAMED_depth"] = preview.render(scene, camera, W, H)
del boxes["boxmarch_frame"]
mesh.uv_layers["BoxQuatXY"].data.foreach_set("uv", uv["BoxQuatXY"])
mesh.uv_layers["BoxQuatZW"].data.foreach_set("uv", uv["BoxQuatZW"])
mesh.update()
bpy.context.view_layer.update()

# An orthographic camera: rays share one direction.
camera.data.type = "ORTHO"
camera.data.ortho_scale = 9.0
result["ortho_view"], result["ortho_projection"] = preview.camera_matrices(scene, camera, W, H)
boxes.boxmarch.sdf = "SPHERE"
result["ORTHO_rgba"], result["ORTHO_depth"] = preview.render(scene, camera, W, H)
camera.data.type = "PERSP"

# The quality knob at its lowest, 40 x 30 px, where the boxes are 1 to 6 px wide: secant steps
# within 0.475 px of a surface, the step limit and one tap for boxes under 3.8 px.
# The TORUS preset as a user's map(): the knob sets a march, and a preset is solved in closed form.
quality_text = bpy.data.texts.new("torus.glsl")
quality_text.write("float map(vec3 p)\n{\n  return sdf_preset_torus(p, box_half);\n}\n")
boxes.boxmarch.sdf = "USER"
boxes.boxmarch.user_text = quality_text.name
boxes.boxmarch.quality = 0.05
result["quality_view"], result["quality_projection"] = preview.camera_matrices(scene, camera, 40, 30)
result["QUALITY_rgba"], result["QUALITY_depth"] = preview.render(scene, camera, 40, 30)
boxes.boxmarch.quality = 1.0
boxes.boxmarch.sdf = "SPHERE"

# The camera inside a box (outside its sphere): only far-side fragments exist, the rays start at
# the eye.
inside = boxes.matrix_world @ mathutils.Vector(centres[0] + rotations[0] @ (0.4 * sizes[0]))
camera.location = inside
camera.rotation_euler = (boxes.matrix_world @ mathutils.Vector(centres[0]) - inside).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start = 0.01
bpy.context.view_layer.update()
result["inside_view"], result["inside_projection"] = preview.camera_matrices(scene, camera, W, H)
result["INSIDE_rgba"], result["INSIDE_depth"] = preview.render(scene, camera, W, H)
camera.location = (7.5, -8.0, 6.0)
camera.rotation_euler = (-camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start = 0.5
bpy.context.view_layer.update()

# Geometry edited and baked again: the preview must drop its cached batch.
shift = np.array([0.0, 0.0, 0.75], np.float32)
moved = mesh_io.read_positions(mesh) + shift
mesh.vertices.foreach_set("co", moved.ravel())
mesh.update()
for ob in scene.objects:
    ob.select_set(ob == boxes)
bpy.context.view_layer.objects.active = boxes
assert bpy.ops.boxmarch.bake() == {"FINISHED"}
bpy.context.view_layer.update()
result["shift"] = shift
result["MOVED_rgba"], result["MOVED_depth"] = preview.render(scene, camera, W, H)

# A chain of three unit boxes along x, faces touching, each drawn as its sphere (shape 1), box i
# the parent of box i + 1: blended into its parent (radius 0.3) a neck joins the spheres where
# they touch (x = 0.5, 1.5). Then the same with no parents: nothing may change.
boxes.hide_viewport = True
chain_arrays = scenes.box_arrays(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]), 1.0, np.eye(3))
chain_mesh = mesh_io.new_mesh("chain", chain_arrays[0], chain_arrays[2], chain_arrays[3], chain_arrays[4])
chain = bpy.data.objects.new("chain", chain_mesh)
scene.collection.objects.link(chain)
chain_mesh.attributes.new("boxmarch_shape", "INT", "POINT").data.foreach_set("value", np.ones(24, np.int32))
chain_mesh.attributes.new("boxmarch_parent", "INT", "POINT").data.foreach_set(
    "value", np.repeat([-1, 0, 1], 8).astype(np.int32))
for ob in scene.objects:
    ob.select_set(ob == chain)
bpy.context.view_layer.objects.active = chain
assert bpy.ops.boxmarch.bake() == {"FINISHED"}
chain.boxmarch.preview = True
chain.boxmarch.blend_radius = 0.3
result["chain_matrix"] = np.array(chain.matrix_world)
camera.location = (1.0, -5.0, 1.5)  # from the side, a little above: the joints in view
camera.rotation_euler = (mathutils.Vector((1.0, 0.0, 0.0)) - camera.location).to_track_quat("-Z", "Y").to_euler()
bpy.context.view_layer.update()
result["chain_view"], result["chain_projection"] = preview.camera_matrices(scene, camera, W, H)
for sdf in ("PER_BOX", "PER_BOX_BLEND"):
    chain.boxmarch.sdf = sdf
    result[f"CHAIN_{sdf}_rgba"], result[f"CHAIN_{sdf}_depth"] = preview.render(scene, camera, W, H)
    result[f"CHAIN_{sdf}_steps"] = preview.render(scene, camera, W, H, output="STEPS")[0]
chain_mesh.attributes.remove(chain_mesh.attributes["boxmarch_parent"])
assert bpy.ops.boxmarch.bake() == {"FINISHED"}
draw.forget()
result["CHAIN_ROOTS_rgba"], result["CHAIN_ROOTS_depth"] = preview.render(scene, camera, W, H)

np.savez_compressed(out_path, **result)
print("preview_check: wrote", out_path)
sys.stdout.flush()
sys.stderr.flush()
os._exit(0)  # the bpy modules 4.2 and 4.5 segfault at interpreter exit once the add-on registered

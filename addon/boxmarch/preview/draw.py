"""Drawing of previewed objects: the raymarch batch, the box outline and the decoded-vector
overlay. Shared by the viewport draw handler and the offscreen render (``preview.render``)."""
from __future__ import annotations

import bpy
import gpu
import numpy as np
from gpu_extras.batch import batch_for_shader

from . import mesh_data, shader as preview_shader, sources

RAW_VECTOR_COLOR = (0.35, 0.75, 1.0, 1.0)      # light blue, as in the seed's Unity script
ROTATED_VECTOR_COLOR = (1.0, 0.55, 0.1, 1.0)   # orange: meets at the submesh origins
OUTLINE_COLOR = (0.05, 0.05, 0.05, 1.0)
SOLID_COLOR = (0.6, 0.6, 0.6, 1.0)

# Batches per mesh datablock, dropped when its geometry changes, a file loads or undo runs
# (handlers in __init__).
_batches: dict = {}
# Why an object is not raymarched, per object name (shown in the panel): not baked, a user SDF
# that does not compile (its outline is drawn instead), a malformed frame property.
errors: dict = {}


def uniform_shader():
    try:
        return gpu.shader.from_builtin("UNIFORM_COLOR")
    except (ValueError, KeyError):  # Blender 3.x name
        return gpu.shader.from_builtin("3D_UNIFORM_COLOR")


def forget(mesh_name=None):
    if mesh_name is None:
        _batches.clear()
    else:
        _batches.pop(mesh_name, None)


def _mesh_batches(ob):
    """(raymarch batch, outline batch, raw vector batch, rotated vector batch) of a baked mesh."""
    key = ob.data.name_full
    if key not in _batches:
        baked = mesh_data.read_baked(ob.data)
        shader = preview_shader.preview_shader("BOX")
        march = batch_for_shader(shader, "TRIS", {
            "pos": baked.positions, "offset_color": baked.offsets, "quat": baked.quaternions,
            "half_extents": baked.half_extents}, indices=baked.triangles)
        lines = uniform_shader()
        outline = batch_for_shader(lines, "LINES", {"pos": baked.positions}, indices=baked.edges)
        vectors = [batch_for_shader(lines, "LINES", {"pos": pairs}) for pairs in mesh_data.vector_lines(baked)]
        _batches[key] = (march, outline, *vectors)
    return _batches[key]


# Custom object property: 9 floats, row-major 3x3, the object frame the baked data is expressed
# in, from Blender's object frame (orthonormal). Set by export presets that write engine axes.
FRAME_PROPERTY = "boxmarch_frame"


def object_frame(ob) -> np.ndarray:
    """The 3x3 frame of ob's baked data (identity unless FRAME_PROPERTY is set)."""
    values = ob.get(FRAME_PROPERTY)
    if values is None:
        return np.eye(3)
    frame = np.asarray(list(values), np.float64)
    if frame.shape != (9,) or not np.allclose(frame.reshape(3, 3) @ frame.reshape(3, 3).T, np.eye(3), atol=1e-5):
        raise ValueError(f"{ob.name}['{FRAME_PROPERTY}'] must be 9 numbers of an orthonormal 3x3 matrix")
    return frame.reshape(3, 3)


def uniform_block_data(object_to_clip, object_to_view, perspective, settings, output_mode=0,
                       base_color=(0.8, 0.8, 0.8, 1.0), frame=None) -> np.ndarray:
    """The BoxmarchPreview block (shaders/glsl/preview.frag.glsl) as std140 float32 words."""
    object_to_clip = np.asarray(object_to_clip, np.float64)
    object_to_view = np.asarray(object_to_view, np.float64)
    data = np.zeros(64, np.float32)
    data[0:16] = object_to_clip.T.ravel()   # GLSL matrices are column-major
    normal = np.eye(4)
    normal[:3, :3] = np.linalg.inv(object_to_view[:3, :3]).T
    data[16:32] = normal.T.ravel()
    frame4 = np.eye(4)
    if frame is not None:
        frame4[:3, :3] = frame
    data[32:48] = frame4.T.ravel()
    view_to_object = np.linalg.inv(object_to_view)
    if perspective:
        data[48:52] = view_to_object @ np.array([0.0, 0.0, 0.0, 1.0])
        data[51] = 1.0
    else:
        direction = (view_to_object @ np.array([0.0, 0.0, -1.0, 0.0]))[:3]
        data[48:51] = direction / np.linalg.norm(direction)
        data[51] = 0.0
    data[52:56] = settings.epsilon, settings.relaxation, settings.max_distance, settings.max_steps
    data[56:60] = base_color
    data.view(np.int32)[60] = output_mode
    return data


def _marching_shader(ob):
    """The object's preview shader, or None (and an error noted) when its user SDF fails."""
    settings = ob.boxmarch
    if settings.sdf != "USER":
        errors.pop(ob.name, None)
        return preview_shader.preview_shader(settings.sdf)
    text = bpy.data.texts.get(settings.user_text)
    if text is None:
        errors[ob.name] = f"no text block named '{settings.user_text}'" if settings.user_text else "choose a text block"
        return None
    try:
        shader = preview_shader.preview_shader("USER", text.as_string())
    except preview_shader.UserSdfError as exc:
        errors[ob.name] = f"{text.name}: {exc}"
        return None
    errors.pop(ob.name, None)
    return shader


def draw_object(ob, view_matrix, projection_matrix, perspective, output_mode=0):
    """Draws one previewed object into the bound framebuffer (depth test on). Returns False when
    it only drew its outline (not baked, or the user SDF did not compile)."""
    matrix_world = np.array(ob.matrix_world, np.float64)
    object_to_view = np.array(view_matrix, np.float64) @ matrix_world
    object_to_clip = np.array(projection_matrix, np.float64) @ object_to_view
    try:
        march, outline, raw_vectors, rotated_vectors = _mesh_batches(ob)
    except mesh_data.NotBakedError as exc:
        errors[ob.name] = str(exc)
        return False
    settings = ob.boxmarch
    shader = _marching_shader(ob)
    try:
        frame = object_frame(ob)
    except ValueError as exc:
        errors[ob.name] = str(exc)
        shader = None
    if shader is not None:
        block = uniform_block_data(object_to_clip, object_to_view, perspective, settings, output_mode,
                                   tuple(ob.color[:3]) + (1.0,), frame)
        ubo = gpu.types.GPUUniformBuf(block.tobytes())
        shader.bind()
        shader.uniform_block(sources.UNIFORM_NAME, ubo)
        march.draw(shader)
    if output_mode != 0:
        return shader is not None
    lines = uniform_shader()
    with gpu.matrix.push_pop():
        gpu.matrix.multiply_matrix(ob.matrix_world)
        lines.bind()
        if settings.show_outline or shader is None:
            lines.uniform_float("color", OUTLINE_COLOR)
            outline.draw(lines)
        if settings.show_vectors:
            lines.uniform_float("color", RAW_VECTOR_COLOR)
            raw_vectors.draw(lines)
            lines.uniform_float("color", ROTATED_VECTOR_COLOR)
            rotated_vectors.draw(lines)
    return shader is not None


def draw_solid(ob, depsgraph):
    """An ordinary mesh object in one flat colour (for the offscreen render)."""
    evaluated = ob.evaluated_get(depsgraph)
    try:
        positions, triangles = mesh_data.read_triangles(evaluated.to_mesh())
    finally:
        evaluated.to_mesh_clear()
    shader = uniform_shader()
    batch = batch_for_shader(shader, "TRIS", {"pos": positions}, indices=triangles)
    with gpu.matrix.push_pop():
        gpu.matrix.multiply_matrix(ob.matrix_world)
        shader.bind()
        shader.uniform_float("color", SOLID_COLOR)
        batch.draw(shader)

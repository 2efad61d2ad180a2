"""Drawing of previewed objects: the raymarch batch, the box outline and the decoded-vector
overlay. Shared by the viewport draw handler and the offscreen render (``preview.render``)."""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Callable

import bpy
import gpu
import numpy as np
from gpu_extras.batch import batch_for_shader

from .. import mesh_io
from ..formats import layouts, presets, shader_sources
from . import mesh_data, occlusion, resolve, skinning
from . import shader as preview_shader

RAW_VECTOR_COLOR = (0.35, 0.75, 1.0, 1.0)      # light blue, as in the seed's Unity script
ROTATED_VECTOR_COLOR = (1.0, 0.55, 0.1, 1.0)   # orange: meets at the submesh origins
OUTLINE_COLOR = (0.05, 0.05, 0.05, 1.0)
SOLID_COLOR = (0.6, 0.6, 0.6, 1.0)

# What a mesh draws from, per (mesh datablock, layout): dropped when the mesh's data changes, a
# file loads or undo runs (handlers in __init__).
_meshes: dict = {}
# What a posed object draws from, per object: rebuilt from _meshes when its pose changes.
_posed: dict = {}
# Why an object is not raymarched, per object name (shown in the panel): not baked, a user SDF
# that does not compile (its outline is drawn instead), a malformed frame property, an Armature
# modifier the preview cannot follow.
errors: dict = {}

# Draw boxes front to back (one index order per view octant) so early depth testing skips the
# marches of hidden boxes; False draws them in the mesh's order (bench/bench_preview_cost.py
# compares the two).
FRONT_TO_BACK = True

# The shader inputs a pose changes: skinning moves positions, normals and tangents; every other
# channel stays as baked.
POSE_INPUTS = ("pos", "ch_normal", "ch_tangent")


def uniform_shader():
    try:
        return gpu.shader.from_builtin("UNIFORM_COLOR")
    except (ValueError, KeyError):  # Blender 3.x name
        return gpu.shader.from_builtin("3D_UNIFORM_COLOR")


def forget(mesh_name=None):
    """Drops what was read from a mesh datablock (every mesh when None), and the poses drawn from it."""
    for key in [k for k in _meshes if mesh_name is None or k[0] == mesh_name]:
        del _meshes[key]
    for key in [k for k, posed in _posed.items() if mesh_name is None or posed.mesh_key[0] == mesh_name]:
        del _posed[key]


def pose_changed(object_name=None) -> bool:
    """Marks an object's pose (every posed object's when None) for recomputation at its next draw.
    Returns whether the object is drawn posed."""
    names = list(_posed) if object_name is None else [object_name]
    for name in names:
        if name in _posed:
            _posed[name].stale = True
    return object_name is None or object_name in _posed


def cached_mesh(mesh_name, layout):
    """What the preview keeps of a mesh datablock in one layout, or None: the same object until
    the mesh's data changes (so a caller can see that a pose change kept it)."""
    return _meshes.get((mesh_name, layout))


def posed_state(object_name):
    """An object's posed drawing (``weights``: the skin weights read once; ``drawn``: the last
    drawing, with ``positions``, ``offsets`` and ``frame()``), or None when it is not drawn posed."""
    return _posed.get(object_name)


def _vertex_buffer(inputs: dict):
    """One GPU vertex buffer holding the float32 (N, k) arrays of ``inputs`` by attribute name."""
    vertex_format = gpu.types.GPUVertFormat()
    for name, values in inputs.items():
        vertex_format.attr_add(id=name, comp_type="F32", len=values.shape[1], fetch_mode="FLOAT")
    vertex_count = len(next(iter(inputs.values())))
    buffer = gpu.types.GPUVertBuf(vertex_format, vertex_count)
    for name, values in inputs.items():
        buffer.attr_fill(name, np.ascontiguousarray(values, np.float32))
    return buffer


@dataclass
class _Drawn:
    """The GPU batches of one object's preview, and the CPU arrays its overlay and poses need."""

    moving: object                # GPUVertBuf of the POSE_INPUTS
    static: object                # GPUVertBuf of the other inputs
    triangles: Callable           # octant -> GPUIndexBuf, boxes front to back for views in it (None: mesh order)
    outline: object               # GPUBatch of the mesh edges (the same vertex buffers)
    positions: np.ndarray         # float32 (N, 3) as drawn
    offsets: np.ndarray           # float64 (N, 3) f, box-local
    frame: Callable               # () -> float64 (N, 3, 3) the frame the layout decodes to (unit columns)
    outward: bool = False         # every box closed and wound outward: back faces may be culled
    # the boxes that may draw occluders (mesh_data.sealed_boxes): all, wound outward (True), none
    # (False), or a GPUIndexBuf of their triangles wound outward (mesh_data.wound_outward)
    sealed: object = True
    vectors: tuple | None = None  # the overlay's two line batches, made when first shown
    marches: dict = field(default_factory=dict)  # octant -> GPUBatch of the preview shader
    occluder_batch: object = None  # GPUBatch of the sealed boxes where only some are sealed

    def march(self, octant: int | None):
        """The batch of the preview shader drawing the boxes front to back for ``octant``."""
        if octant not in self.marches:
            batch = gpu.types.GPUBatch(type="TRIS", buf=self.moving, elem=self.triangles(octant))
            batch.vertbuf_add(self.static)
            self.marches[octant] = batch
        return self.marches[octant]

    def occluders(self, march):
        """The batch the hidden-box pre-pass draws, given the one marching (``march``): that one
        where every box is sealed (mesh_data.sealed_boxes) and wound outward, else one of the
        sealed boxes' triangles wound outward, None where none is sealed (no pre-pass)."""
        if isinstance(self.sealed, bool):
            return march if self.sealed else None
        if self.occluder_batch is None:
            self.occluder_batch = gpu.types.GPUBatch(type="TRIS", buf=self.moving, elem=self.sealed)
            self.occluder_batch.vertbuf_add(self.static)
        return self.occluder_batch


class _OctantTriangles:
    """The triangle index buffer of each view octant (mesh_data.octant_triangles), made when first
    drawn. Held apart from _Mesh so the drawings that share it make no reference cycle: GPU
    buffers must be freed while Blender's GPU context lives, not by the collector at exit."""

    def __init__(self, baked: mesh_data.BakedMesh):
        self.baked = baked
        self.buffers = {}

    def __call__(self, octant: int | None):
        """The buffer for ``octant``; None: the mesh's own triangle order."""
        if octant not in self.buffers:
            triangles = self.baked.triangles if octant is None else mesh_data.octant_triangles(self.baked, octant)
            self.buffers[octant] = gpu.types.GPUIndexBuf(type="TRIS", seq=triangles)
        return self.buffers[octant]


@dataclass
class _Mesh:
    """A baked mesh in one layout: what a pose does not change."""

    baked: mesh_data.BakedMesh
    inputs: dict                  # the shader inputs at rest (mesh_data.layout_inputs)
    static: object                # GPUVertBuf of the inputs not in POSE_INPUTS
    edges: object                 # GPUIndexBuf
    triangles: _OctantTriangles
    sealed: object                # _Drawn.sealed
    rest: _Drawn | None = None


@dataclass
class _Posed:
    """An object following its armature: weights read once, the drawing redone when stale."""

    mesh_key: tuple
    rig_key: tuple                # skinning.rig_key when the weights were read
    weights: skinning.SkinWeights
    drawn: _Drawn | None = None
    stale: bool = True


def _batches(pose_inputs: dict, mesh: _Mesh, positions, offsets, frame) -> _Drawn:
    moving = _vertex_buffer(pose_inputs)
    outline = gpu.types.GPUBatch(type="LINES", buf=moving, elem=mesh.edges)
    return _Drawn(moving=moving, static=mesh.static, triangles=mesh.triangles, outline=outline,
                  positions=positions, offsets=offsets, frame=frame, outward=mesh.baked.outward, sealed=mesh.sealed)


def _normalised(vectors):
    return vectors / np.maximum(np.linalg.norm(vectors, axis=-2, keepdims=True), 1e-30)


def _mesh(mesh, layout) -> _Mesh:
    """The cached rest-pose drawing of ``mesh`` in ``layout``. Raises mesh_data.NotBakedError."""
    key = (mesh.name_full, layout)
    if key not in _meshes:
        baked = mesh_data.read_baked(mesh)
        inputs = mesh_data.layout_inputs(layout, baked)
        static = _vertex_buffer({k: v for k, v in inputs.items() if k not in POSE_INPUTS})
        edges = gpu.types.GPUIndexBuf(type="LINES", seq=baked.edges)
        # the occluders' triangles: the mesh's own where every box is sealed and wound outward,
        # else the sealed boxes' wound outward (mesh_data.wound_outward), or none
        in_sealed = baked.sealed[baked.submesh_of_vertex[baked.triangles[:, 0]]]
        sealed = (bool(in_sealed.all()) if (in_sealed.all() and baked.outward) or not in_sealed.any()
                  else gpu.types.GPUIndexBuf(type="TRIS", seq=mesh_data.wound_outward(
                      baked.positions, baked.triangles[in_sealed], baked.origins, baked.submesh_of_vertex)))
        mesh = _Mesh(baked=baked, inputs=inputs, static=static, edges=edges, triangles=_OctantTriangles(baked),
                     sealed=sealed)
        mesh.rest = _batches({k: v for k, v in inputs.items() if k in POSE_INPUTS}, mesh, baked.positions,
                             mesh_data.box_data_in_object_frame(baked).offsets,
                             lambda: layouts.quaternion_matrices(baked.quaternions))
        _meshes[key] = mesh
    return _meshes[key]


def _posed_drawing(ob, layout, modifier, depsgraph) -> _Drawn:
    """The drawing of ``ob`` in its current pose: the evaluated positions, and for the NORMAL_*
    layouts the normal and tangent moved by each vertex's skinning matrix (skinning.py)."""
    mesh_io.check_skin_modifier(modifier)
    mesh = _mesh(ob.data, layout)
    key, rig_key = (ob.data.name_full, layout), skinning.rig_key(ob, modifier)
    posed = _posed.get(ob.name_full)
    if posed is None or posed.mesh_key != key or posed.rig_key != rig_key:
        posed = _Posed(mesh_key=key, rig_key=rig_key, weights=skinning.read_weights(ob, modifier.object.data))
        _posed[ob.name_full] = posed
    if posed.stale or posed.drawn is None:
        positions = skinning.evaluated_positions(ob, depsgraph, len(mesh.baked.positions))
        inputs = {"pos": positions}
        frame = mesh.rest.frame
        if "ch_normal" in mesh.inputs:  # the frame rides in what skinning moves
            linear = skinning.skin_linear(posed.weights, skinning.bone_deformations(
                ob, modifier, posed.weights.bones, depsgraph))
            normal = np.einsum("nij,nj->ni", linear, mesh.inputs["ch_normal"])
            tangent = mesh.inputs["ch_tangent"].copy()
            tangent[:, :3] = np.einsum("nij,nj->ni", linear, tangent[:, :3])
            inputs.update(ch_normal=normal, ch_tangent=tangent)

            def frame(normal=normal, tangent=tangent):
                axis_y = np.cross(normal, tangent[:, :3]) * tangent[:, 3:]
                return _normalised(np.stack([tangent[:, :3], axis_y, normal], axis=2).astype(np.float64))
        posed.drawn = _batches(inputs, mesh, positions, mesh.rest.offsets, frame)
        posed.stale = False
    return posed.drawn


def drawing(ob, depsgraph) -> _Drawn:
    """What ``ob`` draws from: posed when it has an Armature modifier, else its mesh at rest."""
    layout = ob.boxmarch.layout
    modifier = skinning.armature_modifier(ob)
    if modifier is None:
        _posed.pop(ob.name_full, None)
        return _mesh(ob.data, layout).rest
    return _posed_drawing(ob, layout, modifier, depsgraph)


def _vector_batches(drawn: _Drawn):
    if drawn.vectors is None:
        lines = uniform_shader()
        drawn.vectors = tuple(batch_for_shader(lines, "LINES", {"pos": pairs})
                              for pairs in mesh_data.vector_lines(drawn.positions, drawn.offsets, drawn.frame()))
    return drawn.vectors


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
                       base_color=(0.8, 0.8, 0.8, 1.0), frame=None, viewport_height=1080,
                       occluders=False) -> np.ndarray:
    """The BoxmarchPreview block (shaders/glsl/preview.frag.glsl) as std140 float32 words;
    ``occluders``: the hidden-box pre-pass runs before the march (occlusion.py). mode.y: 1 where
    ``object_to_view`` mirrors, so that the fragment stage knows a box's outer faces wind the other
    way on screen (Blender's GPU module keeps the winding; three.js flips it itself)."""
    object_to_clip = np.asarray(object_to_clip, np.float64)
    object_to_view = np.asarray(object_to_view, np.float64)
    data = np.zeros(76, np.float32)
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
    data.view(np.int32)[60:62] = output_mode, int(np.linalg.det(object_to_view[:3, :3]) < 0.0)
    data[64:67] = settings.quality, viewport_height, (object_to_clip @ view_to_object)[1, 1]  # the projection's y scale
    data[68] = settings.blend_radius if settings.sdf == "PER_BOX_BLEND" else 0.0
    data[69] = float(settings.colour_by_material)
    data[72:74] = float(occluders), occlusion.shape_id(settings.sdf)
    return data


def _marching_shader(ob, resolved: bool, eye_boxes: bool = False):
    """The object's preview shader (``resolved``: the resolved passes' stage; ``eye_boxes``: the
    one-pass stage of the boxes holding the eye), or None (and an error noted) when its user SDF
    fails."""
    settings = ob.boxmarch
    mirror = presets.PRESETS[settings.engine].mirror  # what the engine's local frame does
    if settings.sdf != "USER":
        errors.pop(ob.name, None)
        return preview_shader.preview_shader(settings.sdf, None, mirror, settings.layout, resolved, eye_boxes)
    text = bpy.data.texts.get(settings.user_text)
    if text is None:
        errors[ob.name] = f"no text block named '{settings.user_text}'" if settings.user_text else "choose a text block"
        return None
    try:
        shader = preview_shader.preview_shader("USER", text.as_string(), mirror, settings.layout, resolved, eye_boxes)
    except preview_shader.UserSdfError as exc:
        errors[ob.name] = f"{text.name}: {exc}"
        return None
    errors.pop(ob.name, None)
    return shader


# Cull the back faces of boxes that are closed and wound outward (mesh_data.closed_outward): a
# box's far side is hidden by its own front unless the eye is inside it, and the boxes holding the
# eye are drawn apart with both sides anyway (_draw_sides). False draws every face (the benchmarks
# compare the two).
CULL_BACK_FACES = True


def _draw_sides(shaders, prepare, batch, block, cull, perspective, mirrored, eye_depth_test=None):
    """Draws the marching batch with the BoxmarchPreview words ``block``: in an orthographic view
    every box in one draw by ``shaders[0]``; in a perspective view the boxes not holding the eye by
    ``shaders[0]``, then those holding it (preview.vert.glsl, occlusion.z) by ``shaders[1]``, with
    both sides: their marches start at the eye and write a hit's depth nearer than their fragment,
    the far side, which the first stage's declaration (depth GREATER) forbids. ``cull``: the back
    faces of the first draw culled (front faces when the object's matrix mirrors);
    ``eye_depth_test``: the boxes holding the eye drawn with that depth test (the resolved passes:
    their far side's depth bounds nothing); ``prepare(shader)`` binds a shader and its textures."""
    depth_test = gpu.state.depth_test_get()
    for selection in (1.0, 2.0) if perspective else (0.0,):
        chosen = block.copy()
        chosen[74] = selection
        shader = shaders[1] if selection == 2.0 else shaders[0]
        prepare(shader)
        selected = gpu.types.GPUUniformBuf(chosen.tobytes())  # held until drawn: freeing it unbinds it
        shader.uniform_block(shader_sources.UNIFORM_NAME, selected)
        gpu.state.face_culling_set(("FRONT" if mirrored else "BACK") if cull and selection != 2.0 else "NONE")
        if selection == 2.0 and eye_depth_test is not None:
            gpu.state.depth_test_set(eye_depth_test)
        batch.draw(shader)
    gpu.state.face_culling_set("NONE")
    gpu.state.depth_test_set(depth_test)


def draw_object(ob, view_matrix, projection_matrix, perspective, output_mode=0, depsgraph=None):
    """Draws one previewed object into the bound framebuffer (depth test on). Returns False when
    it only drew its outline (not baked, or the user SDF did not compile). ``depsgraph``: the
    evaluated one a posed object is drawn from (the context's when None). Raises ValueError for an
    Armature modifier the preview cannot follow (nothing drawn)."""
    matrix_world = np.array(ob.matrix_world, np.float64)
    object_to_view = np.array(view_matrix, np.float64) @ matrix_world
    object_to_clip = np.array(projection_matrix, np.float64) @ object_to_view
    try:
        drawn = drawing(ob, depsgraph if depsgraph is not None else bpy.context.evaluated_depsgraph_get())
    except mesh_data.NotBakedError as exc:
        errors[ob.name] = str(exc)
        return False
    except ValueError as exc:
        errors[ob.name] = str(exc)
        raise
    settings = ob.boxmarch
    viewport = gpu.state.viewport_get()

    @functools.cache
    def layers():
        baked = _mesh(ob.data, settings.layout).baked
        return mesh_data.layers_over_view(baked.origins, baked.box_half_extents, object_to_clip, viewport[2], viewport[3])

    occluders = occlusion.occluder_count(settings.sdf, settings.quality)
    occluders = occluders if drawn.sealed is not False and occlusion.used(occluders, layers) else 0
    resolved = resolve.used(occluders, layers)
    shader = resolve.prepared(lambda: _marching_shader(ob, True)) if resolved else None
    eye_shader = shader
    if shader is None:
        resolved = False
        shader = _marching_shader(ob, False)
        eye_shader = _marching_shader(ob, False, eye_boxes=True) if shader is not None and perspective else shader
    try:
        frame = object_frame(ob)
    except ValueError as exc:
        errors[ob.name] = str(exc)
        shader = None
    if shader is not None:
        block = uniform_block_data(object_to_clip, object_to_view, perspective, settings, output_mode,
                                   tuple(ob.color[:3]) + (1.0,), frame, viewport[3], occluders > 0)
        ubo = gpu.types.GPUUniformBuf(block.tobytes())
        batch = drawn.march(mesh_data.view_octant(object_to_view) if FRONT_TO_BACK else None)
        cull, mirrored = drawn.outward and CULL_BACK_FACES, np.linalg.det(object_to_view[:3, :3]) < 0.0

        def draw_sides(prepare, batch, block, eye_depth_test=None):
            _draw_sides((shader, eye_shader), prepare, batch, block, cull, perspective, mirrored, eye_depth_test)

        depth, occluder_framebuffer = (
            occlusion.draw_occluders(drawn.occluders(batch), settings.layout, ubo, occluders, viewport[2], viewport[3],
                                     "FRONT" if mirrored else "BACK")
            if occluders else (occlusion.no_depth(), None))
        if resolved:
            resolve.draw(batch, block, depth, occluder_framebuffer, draw_sides, counting=output_mode == 2)
        else:
            def prepare(marching):
                marching.bind()
                marching.uniform_sampler(shader_sources.OCCLUDER_SAMPLER[2], depth)
            draw_sides(prepare, batch, block)
    if output_mode != 0:
        return shader is not None
    lines = uniform_shader()
    with gpu.matrix.push_pop():
        gpu.matrix.multiply_matrix(ob.matrix_world)
        lines.bind()
        if settings.show_outline or shader is None:
            lines.uniform_float("color", OUTLINE_COLOR)
            drawn.outline.draw(lines)
        if settings.show_vectors:
            raw_vectors, rotated_vectors = _vector_batches(drawn)
            lines.uniform_float("color", RAW_VECTOR_COLOR)
            raw_vectors.draw(lines)
            lines.uniform_float("color", ROTATED_VECTOR_COLOR)
            rotated_vectors.draw(lines)
    return shader is not None


def draw_solid(ob, depsgraph):
    """An ordinary mesh object in one flat colour (for the offscreen render)."""
    evaluated = ob.evaluated_get(depsgraph)
    try:
        mesh = evaluated.to_mesh()
        positions, triangles = mesh_io.read_positions(mesh), mesh_io.read_triangles(mesh)
    finally:
        evaluated.to_mesh_clear()
    shader = uniform_shader()
    batch = batch_for_shader(shader, "TRIS", {"pos": positions}, indices=triangles)
    with gpu.matrix.push_pop():
        gpu.matrix.multiply_matrix(ob.matrix_world)
        shader.bind()
        shader.uniform_float("color", SOLID_COLOR)
        batch.draw(shader)

"""The preview's hidden-box pre-pass (docs/PREVIEW.md, "Hidden boxes"): before an object's boxes
march, the same box mesh is drawn depth-only, pulled in by the vertex stage to the boxes inscribed
in each box's shape (shaders/glsl/box_params.glsl, bm_occluder_*), into a depth texture the size of
the viewport; the marching stage reads it and returns before marching wherever a fragment's box
entry lies behind it. It works on every renderer, including those that run every fragment of a
shader that writes its depth (Mesa llvmpipe, NVIDIA's GL driver: docs/BENCHMARKS.md)."""
from __future__ import annotations

import gpu

from .. import core
from ..formats import shader_sources
from . import shader as preview_shader

# On by default; False draws without the pre-pass (the benchmarks and tests compare the two).
ENABLED = True

DEPTH_FORMAT = "DEPTH_COMPONENT32F"

_targets: dict = {}  # (width, height) -> (depth texture, framebuffer): one size at a time
_unused: list = []   # a 1 x 1 depth texture bound where no pre-pass ran (the shader reads none)


def occluder_count(sdf: str, quality: float = 1.0) -> int:
    """How many pre-pass draws an object of preview shape ``sdf`` makes (0: no pre-pass): the
    preset's occluder boxes (box_params.glsl), all core.occluder_boxes indices for the per-box
    shapes (each box's shape id picks its own), none for a user map(), and none below full
    ``quality`` for a marched shape (PER_BOX_BLEND): the knob's one-tap boxes stand at their
    centre's depth, which may lie behind their own occluders, so the pre-pass would change the
    knob's picture. The shapes solved in closed form (shader_sources.CLOSED_FORM_SHAPES) take no
    one-tap and keep it."""
    if not ENABLED or sdf not in core.SDF_PRESETS + (shader_sources.PER_BOX, shader_sources.PER_BOX_BLEND):
        return 0
    if quality < 1.0 and sdf not in shader_sources.CLOSED_FORM_SHAPES:
        return 0
    if sdf not in core.SDF_PRESETS:
        return core.occluder_boxes("BOX", (1.0, 1.0, 1.0))[0].shape[1]
    return int((core.occluder_boxes(sdf, (1.0, 1.0, 1.0))[1][0].min(axis=1) > 0.0).sum())


# Layers of boxes over the view (mesh_data.layers_over_view) from which the pre-pass runs: below
# it the draws of the occluders cost more than the hidden marches they save. Measured with
# bench/bench_preview_cost.py --sweep (Mesa llvmpipe) and bench/bench_gpu_frame.py (NVIDIA H200):
# docs/BENCHMARKS.md, "GPU cost" (the llvmpipe sweep) and "GPU (NVIDIA H200)".
MIN_LAYERS = 2.0


def used(count: int, layers) -> bool:
    """Whether an object whose preview shape has ``count`` occluder boxes (occluder_count) draws
    the pre-pass: ``layers()`` (its boxes' depth over the view, computed only then) is at least
    MIN_LAYERS."""
    return count > 0 and layers() >= MIN_LAYERS


def shape_id(sdf: str) -> float:
    """The shape id the pre-pass pulls boxes in for: the preset's number, or -1 where each box's
    own id (its parameters' x) decides."""
    return float(core.SDF_PRESETS.index(sdf)) if sdf in core.SDF_PRESETS else -1.0


def _target(width: int, height: int):
    key = (width, height)
    if key not in _targets:
        _targets.clear()  # the viewport was resized
        texture = gpu.types.GPUTexture((width, height), format=DEPTH_FORMAT)
        _targets[key] = (texture, gpu.types.GPUFrameBuffer(depth_slot=texture))
    return _targets[key]


def no_depth():
    """The texture bound to the marching shader's occluder_depth where no pre-pass ran."""
    if not _unused:
        _unused.append(gpu.types.GPUTexture((1, 1), format=DEPTH_FORMAT))
    return _unused[0]


def draw_occluders(batch, layout: str, block, count: int, width: int, height: int, culled_faces: str):
    """Draws ``batch`` (the object's sealed boxes wound outward, draw._Drawn.occluders) ``count``
    times with the pre-pass shader, one occluder index each, into a depth texture of ``width`` x
    ``height`` cleared to 1, with the object's uniform ``block``, ``culled_faces`` culled
    (gpu.state.face_culling_set: the back faces, an occluder box being wound as its box); the GPU
    state is left as found. Returns the texture and the framebuffer it is attached to."""
    texture, framebuffer = _target(width, height)
    shader = preview_shader.occluder_shader(layout)
    state = gpu.state.blend_get(), gpu.state.depth_test_get(), gpu.state.depth_mask_get()
    with framebuffer.bind():
        framebuffer.clear(depth=1.0)
        gpu.state.blend_set("NONE")
        gpu.state.depth_test_set("LESS")
        gpu.state.depth_mask_set(True)
        shader.bind()
        shader.uniform_block(shader_sources.UNIFORM_NAME, block)
        gpu.state.face_culling_set(culled_faces)
        for index in range(count):
            shader.uniform_float(shader_sources.OCCLUDER_INDEX[1], float(index))
            batch.draw(shader)
        gpu.state.face_culling_set("NONE")
    gpu.state.blend_set(state[0])
    gpu.state.depth_test_set(state[1])
    gpu.state.depth_mask_set(state[2])
    return texture, framebuffer


def forget():
    """Drops the GPU textures (before Blender's GPU context goes)."""
    _targets.clear()
    _unused.clear()

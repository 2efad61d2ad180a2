"""The preview's resolved passes (docs/PREVIEW.md, "Hidden boxes"): after the occluder pre-pass
(occlusion.py), the boxes march in passes that write no depth, so that the GPU's depth test runs
before the fragment stage and hidden fragments never run, on renderers that run every fragment of
a shader writing its depth (Mesa llvmpipe, NVIDIA's GL driver: docs/BENCHMARKS.md):

1. visibility: the box mesh against the occluders' depth; each surviving fragment marches and
   keeps the nearest hit's window depth of its pixel in an image (imageAtomicMin on its bits);
2. resolve: a full-screen pass writes that depth into a depth texture;
3. shade: the box mesh against that depth; the fragment whose march (the same program's) gives
   that very depth is shaded, into a colour texture;
4. composite: a full-screen pass writes the colour and depth into the framebuffer drawn to.

The picture is the one-pass march's (tests/test_preview_occluders.py). Blender 4.2 and later: 3.4's
Python API has no images, and marches in one pass there (occlusion.py's in-shader cut)."""
from __future__ import annotations

import gpu
from gpu_extras.batch import batch_for_shader

from ..formats import shader_sources
from . import occlusion
from . import shader as preview_shader

# On by default where available(); False marches in one pass (the benchmarks compare the two).
ENABLED = True

# The uniform block's pass word (preview.occlusion.w) and the pre-pass switch (occlusion.x).
_PASS_WORD, _OCCLUDER_WORD = 75, 72
VISIBILITY, SHADE = 1.0, 2.0

_targets: dict = {}   # (width, height) -> _Targets: one size at a time
_triangle: list = []  # the full-screen triangle's batch


# Why this session's GPU backend cannot build the resolved passes (a shader of theirs failed to
# compile), or None: then every object marches in one pass.
refused = None


def available() -> bool:
    """Whether this Blender can draw the resolved passes: images in shaders, and the compute
    dispatch whose barrier orders the image writes before their reads (Blender 4.2 and later),
    unless their shaders failed to compile here."""
    return refused is None and hasattr(gpu.types.GPUShader, "image") and hasattr(gpu, "compute")


def prepared(marching_shader):
    """The resolved marching stage ``marching_shader()`` returns, with the full-screen and
    barrier shaders compiled first, or None where one of them does not compile on this GPU
    backend: the reason is kept in ``refused``, printed once, and the one-pass march is drawn."""
    global refused
    try:
        for stage in ("resolve_depth", "composite", "composite_steps"):
            preview_shader.fullscreen_shader(stage)
        preview_shader.barrier_shader()
        return marching_shader()
    except RuntimeError as exc:
        refused = str(exc).splitlines()[0]
        print(f"boxmarch: the preview marches in one pass: the resolved passes do not compile here ({refused})")
        return None


# Layers of boxes over the view (mesh_data.layers_over_view) from which the resolved passes pay on Mesa llvmpipe:
# below it their fixed cost (a second marching draw, two full-screen passes that write depth)
# outweighs the hidden fragments they skip. Measured on piles of 500 to 4,000 links at 480 x 480
# (bench/bench_preview_cost.py --sweep, against the pre-pass in one pass): 0.69x at 4.3 layers, 0.83x at 8.6, 1.00x at 17.4,
# 1.33x at 34.6. On an NVIDIA H200 they pay from between 4.8 and 9.8 layers (bench/bench_gpu_frame.py:
# 0.89x at 4.8, 1.11x at 9.8, 1.38x at 19.5): the threshold keeps the software renderer's.
MIN_OVERDRAW = 16.0


def used(occluders: int, layers) -> bool:
    """Whether an object whose pre-pass draws ``occluders`` boxes marches in the resolved passes:
    where they are on and available, and ``layers()`` (its boxes' depth over the view,
    mesh_data.layers_over_view, computed only then) is at least MIN_OVERDRAW."""
    return ENABLED and occluders > 0 and available() and layers() >= MIN_OVERDRAW


class _Targets:
    """The textures and framebuffers of one viewport size. The colour is kept in 32-bit floats,
    as the one-pass march writes it into a float target (preview.render), so that both give the
    same picture; the evaluation counts of the STEPS output go into it too."""

    def __init__(self, width: int, height: int):
        self.size = (width, height)
        self.hit_min = gpu.types.GPUTexture(self.size, format="R32UI")
        self.depth = gpu.types.GPUTexture(self.size, format="DEPTH_COMPONENT32F")
        self.colour = gpu.types.GPUTexture(self.size, format="RGBA32F")
        self.shaded = gpu.types.GPUFrameBuffer(depth_slot=self.depth, color_slots=self.colour)

    def counting(self, occluder_depth):
        """The framebuffer of the visibility pass when it counts: the occluders' depth and the
        colour texture, cleared, where both marching passes add their counts."""
        visible = gpu.types.GPUFrameBuffer(depth_slot=occluder_depth, color_slots=self.colour)
        with visible.bind():
            visible.clear(color=(0.0, 0.0, 0.0, 0.0))
        return visible


def _target(width: int, height: int) -> _Targets:
    key = (width, height)
    if key not in _targets:
        _targets.clear()  # the viewport was resized
        _targets[key] = _Targets(width, height)
    return _targets[key]


def _fullscreen(shader):
    if not _triangle:
        _triangle.append(batch_for_shader(shader, "TRIS", {shader_sources.FULLSCREEN_INPUT[1]: ((-1.0, -1.0), (3.0, -1.0),
                                                                                              (-1.0, 3.0))}))
    _triangle[0].draw(shader)


def _march(batch, block, pass_word, draw_sides, hit_min):
    """One marching pass of the box mesh with ``block`` set to ``pass_word``; the boxes holding
    the eye march from it whatever the depth there (their far side's depth bounds nothing)."""
    chosen = block.copy()
    chosen[_PASS_WORD], chosen[_OCCLUDER_WORD] = pass_word, 0.0

    def prepare(marching):
        marching.bind()
        marching.image(shader_sources.HIT_MIN_IMAGE[3], hit_min)
        marching.uniform_sampler(shader_sources.OCCLUDER_SAMPLER[2], occlusion.no_depth())
    draw_sides(prepare, batch, chosen, eye_depth_test="ALWAYS")


def draw(batch, block, occluder_depth, occluder_framebuffer, draw_sides, counting: bool):
    """Draws the resolved passes of one object into the bound framebuffer: ``batch`` (the box mesh), ``block`` (its BoxmarchPreview words),
    after occlusion.draw_occluders filled ``occluder_depth`` (attached to ``occluder_framebuffer``);
    ``draw_sides(prepare, batch, block, eye_depth_test)`` draws the boxes as draw.py culls them
    with the resolved marching stage (``prepare(shader)`` binding it and its textures before each draw).
    ``counting``: the STEPS output (the evaluation counts of every pass, added into the bound
    framebuffer by the caller's blend). The caller's GPU state is kept."""
    width, height = occluder_depth.width, occluder_depth.height
    targets = _target(width, height)
    state = gpu.state.blend_get(), gpu.state.depth_test_get(), gpu.state.depth_mask_get()
    targets.hit_min.clear(format="UINT", value=(shader_sources.NO_HIT,))
    visible = targets.counting(occluder_depth) if counting else occluder_framebuffer
    gpu.state.blend_set("ADDITIVE" if counting else "NONE")
    with visible.bind():
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(False)
        _march(batch, block, VISIBILITY, draw_sides, targets.hit_min)
    gpu.compute.dispatch(preview_shader.barrier_shader(), 1, 1, 1)
    with targets.shaded.bind():
        if counting:
            targets.shaded.clear(depth=1.0)
        else:
            targets.shaded.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
        resolve_depth = preview_shader.fullscreen_shader("resolve_depth")
        resolve_depth.bind()
        resolve_depth.image(shader_sources.HIT_MIN_IMAGE[3], targets.hit_min)
        gpu.state.color_mask_set(False, False, False, False)
        gpu.state.depth_test_set("ALWAYS")
        gpu.state.depth_mask_set(True)
        _fullscreen(resolve_depth)
        gpu.state.color_mask_set(True, True, True, True)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(False)
        _march(batch, block, SHADE, draw_sides, targets.hit_min)
    gpu.state.blend_set(state[0])
    composite = preview_shader.fullscreen_shader("composite_steps" if counting else "composite")
    composite.bind()
    composite.uniform_sampler(shader_sources.COMPOSITE_SAMPLERS[0][2], targets.colour)
    if not counting:  # the counts' composite reads no depth (a sampler it does not use is not there)
        composite.uniform_sampler(shader_sources.COMPOSITE_SAMPLERS[1][2], targets.depth)
    gpu.state.depth_test_set(state[1])
    gpu.state.depth_mask_set(state[2])
    _fullscreen(composite)


def forget():
    """Drops the GPU textures and batches (before Blender's GPU context goes)."""
    _targets.clear()
    _triangle.clear()

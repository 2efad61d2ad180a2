"""Builds the preview shader through ``gpu.shader.create_from_info`` (Blender 3.4 to 5.x) and
keeps one per (SDF preset or user text, engine mirror, layout); user SDF compile errors become a readable message."""
from __future__ import annotations

import os
import re
import sys
import tempfile

import gpu

from ..formats import shader_sources


class UserSdfError(Exception):
    """The user's map() did not compile. ``line`` is the line in the text block (None when the
    compiler blamed something after it, e.g. a missing brace)."""

    def __init__(self, message: str, line: int | None):
        super().__init__(message)
        self.line = line


# The fragment depth's declared direction: the marched depth is never nearer than the face's
# (preview.frag.glsl clamps it), so GREATER is true and allows early depth testing; ANY (what
# gl_FragDepth implies undeclared) forbids it. Mesa llvmpipe and NVIDIA's OpenGL driver 580 were
# measured not to test early either way (bench/bench_preview_cost.py, bench/bench_gpu_frame.py).
DEPTH_WRITE = "GREATER"
# The declaration of the stage drawing the boxes that hold the eye (eye_boxes): their marches start
# at the eye and write a hit's depth nearer than the fragment (the box's far side).
EYE_BOXES_DEPTH_WRITE = "ANY"

_cache: dict = {}
# User texts that failed, so a broken text is compiled once, not at every redraw.
_failed: dict = {}
# Compiled user texts kept (typing in the text editor makes a new one at each change).
MAX_USER_SHADERS = 8


def _create_info(fragment: str, layout: str, occluder: bool = False, resolved: bool = False,
                 depth_write: str = DEPTH_WRITE):
    """The create-info of the marching shader (its written depth declared ``depth_write``), or with
    ``occluder`` of the hidden-box pre-pass (the same inputs and block; the box mesh pulled in to an
    occluder box, depth only, each occluder's written a margin farther:
    shader_sources.OCCLUDER_FRAGMENT_SOURCE); with ``resolved`` of the resolved passes' marching
    stage (the hit_min image, no depth written)."""
    iface = gpu.types.GPUStageInterfaceInfo("boxmarch_preview_interface")
    for interpolation, type_name, name in shader_sources.STAGE_INTERFACE:
        getattr(iface, interpolation)(type_name, name)
    info = gpu.types.GPUShaderCreateInfo()
    for slot, (type_name, name) in enumerate(shader_sources.VERTEX_INPUTS[layout]):
        info.vertex_in(slot, type_name, name)
    info.vertex_out(iface)
    info.typedef_source(shader_sources.UNIFORM_STRUCT)
    info.uniform_buf(0, shader_sources.UNIFORM_TYPE, shader_sources.UNIFORM_NAME)
    for slot, type_name, name in shader_sources.FRAGMENT_OUTPUTS:
        info.fragment_out(slot, type_name, name)
    if occluder:
        info.push_constant(*shader_sources.OCCLUDER_INDEX)
    else:
        info.sampler(*shader_sources.OCCLUDER_SAMPLER)
    if resolved:
        info.image(*shader_sources.HIT_MIN_IMAGE, qualifiers={"READ", "WRITE"})
    elif hasattr(info, "depth_write"):  # Blender 4+; 3.4 has no declaration
        info.depth_write(depth_write)
    info.vertex_source(shader_sources.vertex_source(layout, occluder))
    info.fragment_source(fragment)
    return info, iface


def _compile_capturing_log(info, echo=True):
    """create_from_info, with the compiler log that Blender prints (to stdout or stderr,
    depending on the version) captured and, when ``echo``, passed on."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    with tempfile.TemporaryFile(mode="w+b") as log:
        for fd in saved:
            os.dup2(log.fileno(), fd)
        try:
            shader = gpu.shader.create_from_info(info)
            error = None
        except Exception as exc:  # Blender raises a plain Exception on compile errors
            shader, error = None, exc
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            for fd, copy in saved.items():
                os.dup2(copy, fd)
                os.close(copy)
        log.seek(0)
        text = log.read().decode("utf-8", "replace")
    if text and echo:
        sys.stderr.write(text)
    return shader, error, text


def _compiled(info, what: str):
    """create_from_info of a shader the add-on writes (no user text): RuntimeError with the
    compiler's log where it fails (``what`` names the shader)."""
    shader, error, log = _compile_capturing_log(info)
    if shader is None:
        raise RuntimeError(f"boxmarch {what} shader failed to compile: {error}\n{log}")
    return shader


# Blender 4+ reformats the driver's log with the line in the message ("| :12:5: Error: <message>");
# 3.4 as "   12 | <source line>" ... "   | Error: <message>"; raw logs say "0:12(5): error: <message>".
_LOCATED_ERROR = re.compile(r"\|\s*:(\d+):\d+:\s*error:?\s*(.*)", re.I)
_SOURCE_LINE = re.compile(r"^\s*(\d+)\s*\|")
_BLENDER_ERROR = re.compile(r"\|\s*error:?\s*(.*)", re.I)
_DRIVER_ERROR = re.compile(r"\b\d+:(\d+)\(\d+\):\s*error:?\s*(.*)", re.I)


def _located(line: int, message: str):
    if line >= shader_sources.USER_END_LINE:
        return f"after the end of the text: {message}", None
    return f"line {line}: {message}", line


def _first_error(log: str):
    """(message, line as the log numbers it, or None) of the first error in a compiler log.
    Blender 3.4 to 4.2 and 5.0 print the numbered source line before its errors; 4.5 prints
    errors it could not place first and the numbered line after them."""
    for raw in log.splitlines():
        match = _LOCATED_ERROR.search(raw)
        if match:
            return match.group(2).strip(), int(match.group(1))
    message = line = None
    for raw in log.splitlines():
        numbered = _SOURCE_LINE.match(raw)
        if numbered and line is None:
            line = int(numbered.group(1))
        match = _BLENDER_ERROR.search(raw)
        if match and message is None:
            message = match.group(1).strip()
        match = _DRIVER_ERROR.search(raw)
        if match and message is None:
            message, line = match.group(2).strip(), int(match.group(1))
        if message is not None and line is not None:
            return message, line
    if message is not None:
        return message, None
    errors = [line.strip() for line in log.splitlines() if "error" in line.lower()]
    return (errors[0] if errors else "the shader did not compile (see the system console)"), None


def describe_compile_error(log: str, line_offset: int = 0):
    """(message, user line or None) from a compiler log of a shader holding user text, whose
    line numbers are ``line_offset`` past the text's own (see _log_line_offset)."""
    message, line = _first_error(log)
    return _located(line - line_offset, message) if line is not None else (message, None)


# Text with a syntax error on its line 3: where a log places it shows how that Blender numbers
# the user's lines (4.5 adds the length of its own code before the fragment source; the others
# keep the #line numbering of shader_sources.user_map_source).
_CALIBRATION_TEXT = "float map(vec3 p)\n{\n  return 1.0 +;\n}\n"
_line_offsets: dict = {}


def _log_line_offset(sdf, local_mirror, layout) -> int:
    key = (sdf, local_mirror, layout)
    if key not in _line_offsets:
        info, iface = _create_info(shader_sources.fragment_source(sdf, _CALIBRATION_TEXT, local_mirror), layout)
        _shader, _error, log = _compile_capturing_log(info, echo=False)
        del iface
        line = _first_error(log)[1]
        _line_offsets[key] = line - 3 if line is not None else 0
    return _line_offsets[key]


def preview_shader(sdf: str = "BOX", user_text: str | None = None, local_mirror=(1.0, 1.0, 1.0),
                   layout: str = "CLASSIC", resolved: bool = False, eye_boxes: bool = False):
    """The compiled preview shader for a preset, or for user text defining ``float map(vec3 p)``,
    as an engine with ``local_mirror`` sees it, reading the channels of engine ``layout``;
    ``resolved``: the marching stage of the resolved passes (preview/resolve.py); ``eye_boxes``:
    the one-pass stage that draws the boxes holding the eye (its depth declared ANY). Raises
    UserSdfError with the line for user text that does not compile."""
    eye_boxes = eye_boxes and not resolved  # the resolved passes write no depth: one stage for all
    depth_write = EYE_BOXES_DEPTH_WRITE if eye_boxes else DEPTH_WRITE
    key = (sdf, user_text, tuple(float(v) for v in local_mirror), layout, "RESOLVED" if resolved else depth_write)
    if key in _cache:
        return _cache[key]
    if key in _failed:
        raise UserSdfError(*_failed[key])
    info, iface = _create_info(shader_sources.fragment_source(sdf, user_text, local_mirror, resolved, eye_boxes),
                               layout, resolved=resolved, depth_write=depth_write)
    shader, error, log = _compile_capturing_log(info)
    del iface  # the create-info refers to it until compiled
    if shader is None:
        if user_text is None:
            raise RuntimeError(f"boxmarch preview shader failed to compile: {error}\n{log}")
        _failed[key] = describe_compile_error(log, _log_line_offset(sdf, key[2], layout))
        raise UserSdfError(*_failed[key])
    if user_text is not None:
        user_keys = [k for k in _cache if k[1] is not None]
        for old in user_keys[:max(0, len(user_keys) - MAX_USER_SHADERS + 1)]:
            del _cache[old]
    _cache[key] = shader
    return shader


def occluder_shader(layout: str = "CLASSIC"):
    """The compiled pre-pass shader of the hidden-box cut for engine ``layout``'s channels."""
    key = ("OCCLUDER", None, None, layout, None)
    if key not in _cache:
        info, iface = _create_info(shader_sources.OCCLUDER_FRAGMENT_SOURCE, layout, occluder=True)
        _cache[key] = _compiled(info, "occluder")
        del iface  # the create-info refers to it until compiled
    return _cache[key]


def fullscreen_shader(stage: str):
    """A compiled full-screen stage of the resolved passes (shader_sources.fullscreen_source:
    'resolve_depth', 'composite' or 'composite_steps'), drawn over a triangle covering the view."""
    key = ("FULLSCREEN", stage, None, None, None)
    if key not in _cache:
        info = gpu.types.GPUShaderCreateInfo()
        info.vertex_in(0, *shader_sources.FULLSCREEN_INPUT)
        if stage == "resolve_depth":
            info.image(*shader_sources.HIT_MIN_IMAGE, qualifiers={"READ"})
        else:
            for sampler in shader_sources.COMPOSITE_SAMPLERS:
                info.sampler(*sampler)
        for slot, type_name, name in shader_sources.FRAGMENT_OUTPUTS:
            info.fragment_out(slot, type_name, name)
        info.vertex_source(shader_sources.fullscreen_source("vertex"))
        info.fragment_source(shader_sources.fullscreen_source(stage))
        _cache[key] = _compiled(info, stage)
    return _cache[key]


def barrier_shader():
    """A compute shader that does nothing: Blender's gpu.compute.dispatch issues the memory barrier
    for image access and texture fetches after it, the only barrier its Python API offers, which
    the resolved passes need between the image writes of one draw and the reads of the next."""
    key = ("BARRIER", None, None, None, None)
    if key not in _cache:
        info = gpu.types.GPUShaderCreateInfo()
        info.local_group_size(1, 1, 1)
        info.compute_source("void main()\n{\n}\n")
        _cache[key] = _compiled(info, "barrier")
    return _cache[key]


def clear_cache():
    _cache.clear()
    _failed.clear()

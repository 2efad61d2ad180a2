"""Headless OpenGL through EGL for the benchmarks (bench_gpu_frame.py): a context without a
window, programs, an offscreen framebuffer, GPU timer and statistics queries, read-back.
Needs numpy and PyOpenGL only."""
import ctypes
import os
import sys

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
from OpenGL import EGL, GL  # noqa: E402
from OpenGL.raw.GL.VERSION.GL_3_3 import glGetQueryObjectui64v  # noqa: E402

WARMUP, MAX_FRAMES, BUDGET = 3, 200, 0.5


def egl_display():
    """EGL's default display, or else the first EGL device's (EGL_EXT_platform_device)."""
    major, minor = EGL.EGLint(), EGL.EGLint()
    display = EGL.eglGetDisplay(EGL.EGL_DEFAULT_DISPLAY)
    if display and EGL.eglInitialize(display, ctypes.pointer(major), ctypes.pointer(minor)):
        return display
    from OpenGL.EGL.EXT.device_base import eglQueryDevicesEXT
    from OpenGL.EGL.EXT.platform_base import eglGetPlatformDisplayEXT
    from OpenGL.EGL.EXT.platform_device import EGL_PLATFORM_DEVICE_EXT

    devices, count = (EGL.EGLDeviceEXT * 8)(), EGL.EGLint()
    if eglQueryDevicesEXT(8, devices, ctypes.pointer(count)) and count.value:
        display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[0], None)
        if display and EGL.eglInitialize(display, ctypes.pointer(major), ctypes.pointer(minor)):
            return display
    sys.exit("no EGL display (Mesa without a display server: EGL_PLATFORM=surfaceless)")


def egl_context():
    """A current OpenGL 4.3 core context on an EGL display, no surface."""
    display = egl_display()
    config = EGL.EGLConfig()
    count = EGL.EGLint()
    # a pbuffer config: eglChooseConfig's default asks for windows, which a headless display has none of
    attributes = (EGL.EGLint * 5)(EGL.EGL_RENDERABLE_TYPE, EGL.EGL_OPENGL_BIT, EGL.EGL_SURFACE_TYPE, EGL.EGL_PBUFFER_BIT,
                                  EGL.EGL_NONE)
    if not EGL.eglChooseConfig(display, attributes, ctypes.pointer(config), 1, ctypes.pointer(count)) or not count.value:
        sys.exit("no EGL config with desktop OpenGL")
    EGL.eglBindAPI(EGL.EGL_OPENGL_API)
    context_attributes = (EGL.EGLint * 7)(EGL.EGL_CONTEXT_MAJOR_VERSION, 4, EGL.EGL_CONTEXT_MINOR_VERSION, 3,
                                          EGL.EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                          EGL.EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL.EGL_NONE)
    context = EGL.eglCreateContext(display, config, EGL.EGL_NO_CONTEXT, context_attributes)
    if not context or not EGL.eglMakeCurrent(display, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, context):
        sys.exit("no OpenGL 4.3 core context")
    return display, context


_logged = set()


def program(vertex, fragment):
    return _linked(((GL.GL_VERTEX_SHADER, vertex), (GL.GL_FRAGMENT_SHADER, fragment)))


def compute_program(source):
    return _linked(((GL.GL_COMPUTE_SHADER, source),))


def _linked(stages):
    """A program of (stage, source) pairs; exits with the driver's log where one fails to compile
    or the program to link."""
    shaders = []
    for stage, source in stages:
        shader = GL.glCreateShader(stage)
        GL.glShaderSource(shader, str(source))
        GL.glCompileShader(shader)
        log = GL.glGetShaderInfoLog(shader)
        log = (log.decode() if isinstance(log, bytes) else log).strip()
        if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
            sys.exit(f"shader compile failed:\n{log}")
        if log and log not in _logged:  # warnings: the driver's word on what it does with the source
            _logged.add(log)
            print(f"compiler log: {log}")
        shaders.append(shader)
    handle = GL.glCreateProgram()
    for shader in shaders:
        GL.glAttachShader(handle, shader)
    GL.glLinkProgram(handle)
    if not GL.glGetProgramiv(handle, GL.GL_LINK_STATUS):
        sys.exit(f"link failed:\n{GL.glGetProgramInfoLog(handle)}")
    return handle


def storage_buffers(values, output_bytes):
    """``values`` (float32) as shader storage buffer 0 and ``output_bytes`` for the shader to write
    as buffer 1, bound; buffer 1 stays bound to GL_SHADER_STORAGE_BUFFER for reading back."""
    values = np.ascontiguousarray(values, np.float32)
    buffers = GL.glGenBuffers(2)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffers[0])
    GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, values.nbytes, values, GL.GL_STATIC_DRAW)
    GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, 0, buffers[0])
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffers[1])
    GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, output_bytes, None, GL.GL_DYNAMIC_READ)
    GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, 1, buffers[1])


def framebuffer(width, height):
    """(framebuffer, colour, depth): RGBA16F colour, 24-bit depth + stencil, as the viewport's."""
    fbo = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, fbo)
    buffers = GL.glGenRenderbuffers(2)
    for buffer, storage, attachment in ((buffers[0], GL.GL_RGBA16F, GL.GL_COLOR_ATTACHMENT0),
                                        (buffers[1], GL.GL_DEPTH24_STENCIL8, GL.GL_DEPTH_STENCIL_ATTACHMENT)):
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, buffer)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, storage, width, height)
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, buffer)
    if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
        sys.exit("framebuffer incomplete")
    GL.glViewport(0, 0, width, height)
    return fbo


def timed_frames(draw, frames=None):
    """GPU milliseconds of each of ``frames`` frames (adaptive: about BUDGET seconds) after WARMUP."""
    for _ in range(WARMUP):
        draw()
    GL.glFinish()
    if frames is None:
        first = timed_frames_exact(draw, 1)[0]
        frames = int(np.clip(BUDGET * 1e3 / max(first, 1e-3), 5, MAX_FRAMES))
    return timed_frames_exact(draw, frames)


def timed_frames_exact(draw, frames):
    queries = GL.glGenQueries(frames)
    for query in queries:
        GL.glBeginQuery(GL.GL_TIME_ELAPSED, query)
        draw()
        GL.glEndQuery(GL.GL_TIME_ELAPSED)
    GL.glFinish()
    elapsed = ctypes.c_uint64()
    times = []
    for query in queries:  # the raw entry point: PyOpenGL's wrapper has no array type for 64-bit results
        glGetQueryObjectui64v(query, GL.GL_QUERY_RESULT, ctypes.byref(elapsed))
        times.append(elapsed.value * 1e-6)
    GL.glDeleteQueries(frames, queries)
    return np.array(times)


def extensions():
    return {GL.glGetStringi(GL.GL_EXTENSIONS, i).decode() for i in range(GL.glGetIntegerv(GL.GL_NUM_EXTENSIONS))}


def counted(target, draw):
    """A query's count over one frame (e.g. fragment shader invocations), or None without the extension."""
    if "GL_ARB_pipeline_statistics_query" not in extensions():
        draw()
        return None
    query = GL.glGenQueries(1)[0]
    GL.glBeginQuery(target, query)
    draw()
    GL.glEndQuery(target)
    value = ctypes.c_uint64()
    glGetQueryObjectui64v(query, GL.GL_QUERY_RESULT, ctypes.byref(value))
    GL.glDeleteQueries(1, [query])
    return int(value.value)


def read_back(width, height):
    """(rgba float32 (H, W, 4), depth float32 (H, W)), row 0 at the top."""
    GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
    rgba = np.frombuffer(GL.glReadPixels(0, 0, width, height, GL.GL_RGBA, GL.GL_FLOAT), np.float32)
    depth = np.frombuffer(GL.glReadPixels(0, 0, width, height, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT), np.float32)
    return rgba.reshape(height, width, 4)[::-1], depth.reshape(height, width)[::-1]

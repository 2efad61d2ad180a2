"""The viewport preview's draw of one object (preview/draw.py draw_object) in raw OpenGL 4.3, for
the GPU benchmarks that run where Blender is absent (bench_gpu_frame.py, bench_gpu_triangles.py):
the same shaders (written by gpu_frame_data.py from formats/shader_sources.py behind the
declarations Blender's GL backend makes), vertex buffers, uniform block words and GPU state, pass
by pass:

* one pass: the march, every face, the mesh's triangle order or the view octant's: in a
  perspective view the boxes not holding the eye, then those holding it by the stage that declares
  no depth (BM_EYE_BOXES: their marches from the eye write a depth nearer than the fragment; the
  block's occlusion.z selects them), in an orthographic one every box in one draw;
* back faces culled (draw.CULL_BACK_FACES): in the first of those draws;
* the occluder pre-pass (preview/occlusion.py): the box mesh pulled in to each occluder box,
  depth only, into a DEPTH_COMPONENT32F texture the march reads (occlusion.x);
* the resolved passes (preview/resolve.py): visibility (no depth written, the nearest hit kept in
  an R32UI image by imageAtomicMin), the barrier (Blender issues it after a no-op compute
  dispatch: both are drawn here), resolve (full screen, hit depth into a depth texture), shade,
  composite (full screen, colour and depth into the framebuffer drawn to).

Needs numpy and PyOpenGL (gl_headless.py)."""
import numpy as np

from bench.gl_headless import GL, compute_program, program

# BoxmarchPreview's words (preview/draw.py uniform_block_data): occlusion.x (pre-pass ran), .y
# (its shape id), .z (which boxes a draw takes: 0 all, 1 those not holding the eye, 2 those
# holding it), .w (resolved pass: 1 visibility, 2 shade)
WORDS = {"occluder": 72, "shape": 73, "selection": 74, "pass": 75}
VISIBILITY, SHADE = 1.0, 2.0
NO_HIT = 0x3F800000  # formats/shader_sources.NO_HIT, the bits of 1.0
HIT_MIN_UNIT = 1     # shader_sources.HIT_MIN_IMAGE's slot
BARRIER_SOURCE = "#version 430 core\nlayout(local_size_x = 1) in;\nvoid main()\n{\n}\n"


def vertex_array(data, names):
    """One VAO of the preview's vertex inputs (attribute i = names[i], as the create-info declares
    them) and an element buffer per triangle order ({order: (buffer, index count)})."""
    vao = GL.glGenVertexArrays(1)
    GL.glBindVertexArray(vao)
    for location, name in enumerate(names):
        values = np.ascontiguousarray(data[f"input_{name}"], np.float32)
        buffer = GL.glGenBuffers(1)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, values.nbytes, values, GL.GL_STATIC_DRAW)
        GL.glEnableVertexAttribArray(location)
        GL.glVertexAttribPointer(location, values.shape[1], GL.GL_FLOAT, GL.GL_FALSE, 0, None)
    elements = {}
    for order in ("file", "octant"):
        triangles = np.ascontiguousarray(data[f"triangles_{order}"], np.uint32)
        buffer = GL.glGenBuffers(1)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, buffer)
        GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, triangles.nbytes, triangles, GL.GL_STATIC_DRAW)
        elements[order] = (buffer, triangles.size)
    return vao, elements


def _texture(width, height, internal):
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, internal, width, height)
    for parameter in (GL.GL_TEXTURE_MIN_FILTER, GL.GL_TEXTURE_MAG_FILTER):
        GL.glTexParameteri(GL.GL_TEXTURE_2D, parameter, GL.GL_NEAREST)
    return texture


def _framebuffer(depth, colour=None):
    fbo = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, fbo)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, depth, 0)
    if colour is None:
        GL.glDrawBuffer(GL.GL_NONE)
    else:
        GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, colour, 0)
    if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError("gl_preview: framebuffer incomplete")
    return fbo


class PreviewObject:
    """One previewed object's GPU data and programs, drawn as draw_object draws it."""

    def __init__(self, data):
        names = [str(n) for n in data["input_names"]]
        self.vao, self.elements = vertex_array(data, names)
        self.block = np.array(data["uniform_block"], np.float32)
        self.occluders = int(data["occluder_count"])
        self.shape_id = float(data["occluder_shape_id"])
        self.cull_face = GL.GL_FRONT if bool(data["mirrored"]) else GL.GL_BACK
        self.outward = bool(data["outward"])
        marching = {kind[len("source_fragment_"):]: str(data[kind]) for kind in data
                    if kind.startswith("source_fragment_")}
        self.programs = {kind: program(data["source_vertex"], source) for kind, source in marching.items()}
        self.programs["occluder"] = program(data["source_occluder_vertex"], data["source_occluder_fragment"])
        fullscreen_vertex = str(data["source_fullscreen_vertex"])
        for stage in ("resolve_depth", "composite"):
            self.programs[stage] = program(fullscreen_vertex, data[f"source_fullscreen_{stage}"])
        self.barrier = compute_program(BARRIER_SOURCE)
        for handle in self.programs.values():
            index = GL.glGetUniformBlockIndex(handle, "_preview")
            if index != GL.GL_INVALID_INDEX:
                GL.glUniformBlockBinding(handle, index, 0)
        self._set_samplers()
        self._blocks = {}
        self.triangle = fullscreen_triangle()
        self.no_depth = _texture(1, 1, GL.GL_DEPTH_COMPONENT32F)
        self.size = None
        self.draws = 0  # draw calls made (the benchmarks report a frame's)

    def _set_samplers(self):
        for handle in self.programs.values():
            GL.glUseProgram(handle)
            for name, unit in (("occluder_depth", 0), ("shaded_colour", 0), ("shaded_depth", 1),
                               ("hit_min", HIT_MIN_UNIT)):
                location = GL.glGetUniformLocation(handle, name)
                if location >= 0:
                    GL.glUniform1i(location, unit)

    def _block(self, quality, height, **words):
        """A uniform buffer of the block with quality.x, quality.y and the occlusion words set
        (made once per combination, as draw.py makes one per draw)."""
        key = (quality, height, tuple(sorted(words.items())))
        if key not in self._blocks:
            block = self.block.copy()
            block[64:66] = quality, height
            for word, value in words.items():
                block[WORDS[word]] = value
            buffer = GL.glGenBuffers(1)
            GL.glBindBuffer(GL.GL_UNIFORM_BUFFER, buffer)
            GL.glBufferData(GL.GL_UNIFORM_BUFFER, block.nbytes, block, GL.GL_STATIC_DRAW)
            self._blocks[key] = buffer
        return self._blocks[key]

    def _targets(self, width, height):
        """The pre-pass's depth texture and framebuffer, and the resolved passes' hit_min image,
        depth and colour textures and framebuffer, of one size."""
        if self.size != (width, height):
            self.size = (width, height)
            self.occluder_depth = _texture(width, height, GL.GL_DEPTH_COMPONENT32F)
            self.occluder_fbo = _framebuffer(self.occluder_depth)
            self.hit_min = _texture(width, height, GL.GL_R32UI)
            self.shaded_depth = _texture(width, height, GL.GL_DEPTH_COMPONENT32F)
            self.shaded_colour = _texture(width, height, GL.GL_RGBA32F)
            self.shaded_fbo = _framebuffer(self.shaded_depth, self.shaded_colour)

    def _draw(self, order):
        buffer, count = self.elements[order]
        GL.glBindVertexArray(self.vao)
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, buffer)
        GL.glDrawElements(GL.GL_TRIANGLES, count, GL.GL_UNSIGNED_INT, None)
        self.draws += 1

    def _draw_sides(self, order, cull, quality, height, eye_depth_test=False, eye_program=None, **words):
        """draw.py _draw_sides: in an orthographic view every box in one draw; in a perspective one
        the boxes not holding the eye (back faces culled where ``cull``), then those holding it with
        both sides, by ``eye_program`` where given (the one-pass march's BM_EYE_BOXES stage; with
        ``eye_depth_test``, the resolved passes, whatever the depth there)."""
        perspective = self.block[51] > 0.5  # the eye's w: a position, not a direction
        for selection in (1.0, 2.0) if perspective else (0.0,):
            if selection == 2.0 and eye_program is not None:
                GL.glUseProgram(eye_program)
            GL.glBindBufferBase(GL.GL_UNIFORM_BUFFER, 0, self._block(quality, height, selection=selection, **words))
            if cull and selection == 1.0:
                GL.glEnable(GL.GL_CULL_FACE)
                GL.glCullFace(self.cull_face)
            else:
                GL.glDisable(GL.GL_CULL_FACE)
            if selection == 2.0 and eye_depth_test:
                GL.glDepthFunc(GL.GL_ALWAYS)
            self._draw(order)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDepthFunc(GL.GL_LEQUAL)

    def _occluder_pass(self, order, cull, height, target):
        """occlusion.draw_occluders: the mesh once per occluder index, depth only (LESS)."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.occluder_fbo)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)
        GL.glDepthFunc(GL.GL_LESS)
        handle = self.programs["occluder"]
        GL.glUseProgram(handle)
        GL.glBindBufferBase(GL.GL_UNIFORM_BUFFER, 0, self._block(1.0, height, occluder=1.0, shape=self.shape_id))
        if cull:
            GL.glEnable(GL.GL_CULL_FACE)
            GL.glCullFace(self.cull_face)
        location = GL.glGetUniformLocation(handle, "occluder_index")
        for index in range(self.occluders):
            GL.glUniform1f(location, float(index))
            self._draw(order)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDepthFunc(GL.GL_LEQUAL)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, target)

    def _resolved_passes(self, order, cull, height, target):
        """resolve.draw after the pre-pass, into ``target``."""
        marching = self.programs["resolved"]
        GL.glClearTexImage(self.hit_min, 0, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_INT, np.array([NO_HIT], np.uint32))
        GL.glBindImageTexture(HIT_MIN_UNIT, self.hit_min, 0, GL.GL_FALSE, 0, GL.GL_READ_WRITE, GL.GL_R32UI)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.no_depth)
        # visibility: against the occluders' depth (their framebuffer), no depth written
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.occluder_fbo)
        GL.glDepthMask(GL.GL_FALSE)
        GL.glUseProgram(marching)
        self._draw_sides(order, cull, 1.0, height, True, occluder=0.0, shape=self.shape_id, **{"pass": VISIBILITY})
        GL.glUseProgram(self.barrier)
        GL.glDispatchCompute(1, 1, 1)
        GL.glMemoryBarrier(GL.GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL.GL_TEXTURE_FETCH_BARRIER_BIT)
        # resolve the kept depth, then shade against it
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.shaded_fbo)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        GL.glUseProgram(self.programs["resolve_depth"])
        GL.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)
        GL.glDepthFunc(GL.GL_ALWAYS)
        self._fullscreen()
        GL.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
        GL.glDepthFunc(GL.GL_LEQUAL)
        GL.glDepthMask(GL.GL_FALSE)
        GL.glUseProgram(marching)
        self._draw_sides(order, cull, 1.0, height, True, occluder=0.0, shape=self.shape_id, **{"pass": SHADE})
        # composite into the target with the viewport's state
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, target)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glUseProgram(self.programs["composite"])
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.shaded_colour)
        GL.glActiveTexture(GL.GL_TEXTURE1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.shaded_depth)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        self._fullscreen()

    def _fullscreen(self):
        GL.glBindVertexArray(self.triangle)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        self.draws += 1

    def draw(self, target, width, height, fragment="depth_greater", order="octant", quality=1.0, cull=False,
             occluders=False, resolved=False):
        """One frame into framebuffer ``target`` (cleared, depth test LESS_EQUAL, depth writes: the
        preview's state): the march with fragment stage ``fragment`` in triangle ``order``;
        ``cull``: back faces culled; ``occluders``: the pre-pass first (at quality 1 only, as
        occlusion.occluder_count); ``resolved``: then the resolved passes."""
        self._targets(width, height)
        begin_frame(target, width, height)
        cull = cull and self.outward
        prepass = occluders and self.occluders > 0 and quality == 1.0
        if prepass:
            self._occluder_pass(order, cull, height, target)
        if prepass and resolved:
            self._resolved_passes(order, cull, height, target)
            return
        GL.glUseProgram(self.programs[fragment])
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.occluder_depth if prepass else self.no_depth)
        self._draw_sides(order, cull, quality, height, eye_program=self.programs["eye_boxes"],
                         occluder=float(prepass), shape=self.shape_id)


def shipped_arguments(data, size: str) -> dict:
    """PreviewObject.draw's arguments for what draw_object draws at ``size`` ('960x540') by
    default: back faces culled; the pre-pass where the boxes lie occlusion.MIN_LAYERS layers deep
    or more, and the resolved passes from resolve.MIN_OVERDRAW on (both recorded in ``data`` by
    gpu_frame_data.preview_facts)."""
    layers = float(data[f"layers_{size}"])
    arguments = dict(cull=True)
    if layers >= float(data["min_layers"]):
        arguments["occluders"] = True
        if layers >= float(data["min_overdraw"]):
            arguments["resolved"] = True
    return arguments


def begin_frame(target, width, height):
    """Binds framebuffer ``target``, clears it and sets the viewport's state (depth test
    LESS_EQUAL, depth writes, no blending), as Blender's viewport draws a previewed object."""
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, target)
    GL.glViewport(0, 0, width, height)
    GL.glDisable(GL.GL_BLEND)
    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glDepthFunc(GL.GL_LEQUAL)
    GL.glDepthMask(GL.GL_TRUE)
    GL.glClearColor(0.0, 0.0, 0.0, 0.0)
    GL.glClearDepth(1.0)
    GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)


def fullscreen_triangle():
    """A VAO of one triangle covering the viewport (clip-space xy at attribute 0)."""
    vao = GL.glGenVertexArrays(1)
    GL.glBindVertexArray(vao)
    triangle = np.array([-1.0, -1.0, 3.0, -1.0, -1.0, 3.0], np.float32)
    buffer = GL.glGenBuffers(1)
    GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
    GL.glBufferData(GL.GL_ARRAY_BUFFER, triangle.nbytes, triangle, GL.GL_STATIC_DRAW)
    GL.glEnableVertexAttribArray(0)
    GL.glVertexAttribPointer(0, 2, GL.GL_FLOAT, GL.GL_FALSE, 0, None)
    return vao

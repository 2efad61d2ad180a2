"""GLSL sources of the viewport preview and the interface Blender's create-info declares for them.

Blender-free (no ``bpy``), so the shader tests assemble exactly what the add-on compiles.
"""
from __future__ import annotations

from pathlib import Path

from .. import core
from . import layouts

_PACKAGE = Path(__file__).resolve().parent.parent


def shader_dir() -> Path:
    """The ``shaders`` folder: inside the installed package, or at the top of a checkout."""
    for candidate in (_PACKAGE / "shaders", _PACKAGE.parent.parent / "shaders"):
        if (candidate / "glsl" / "sdf.glsl").is_file():
            return candidate
    raise FileNotFoundError(f"boxmarch shaders not found next to {_PACKAGE}")


def read_glsl(name: str) -> str:
    return (shader_dir() / "glsl" / name).read_text()


# The create-info of the preview shader. Types are Blender's create-info type names.
# Per engine layout (boxmarch/formats/layouts.py): pos and the layout's per-vertex channels but those of
# its box parameters (Layout.channels less Layout.param_channels), "ch_" + the channel's name in
# lower case (COLOR -> ch_color, UV1 -> ch_uv1), as layouts.channels() writes them; ch_half:
# per-vertex half-extents where the layout has none per vertex (CLASSIC carries only the largest,
# the preview derives them from the bake; NORMAL_COLOR's table read at the vertex's index).
_CHANNEL_TYPES = {"COLOR": "VEC4", "NORMAL": "VEC3", "TANGENT": "VEC4"}
# The box's parameters, from the layout's channels or box table, and its parent box in its own
# local coordinates (box_params.glsl: box_parent_origin, box_parent_q, box_parent_half).
_PARAMS = (("VEC4", "ch_params"), ("VEC4", "ch_parent_origin"), ("VEC4", "ch_parent_q"), ("VEC4", "ch_parent_half"))


def _vertex_inputs(layout: layouts.Layout) -> tuple:
    frame = tuple((_CHANNEL_TYPES.get(name, "VEC2"), "ch_" + name.lower())
                  for name in layout.channels if name not in layout.param_channels)
    half = () if layout.half_extents_per_vertex else (("VEC3", "ch_half"),)
    return (("VEC3", "pos"), *frame, *half, *_PARAMS)


VERTEX_INPUTS = {name: _vertex_inputs(layout) for name, layout in layouts.LAYOUTS.items()}
# (interpolation, type, name): the axes are interpolated as an engine interpolates its normal and
# tangent (constant over a rigid box); the half-extents are constant over a submesh.
STAGE_INTERFACE = (("smooth", "VEC3", "obj_pos"), ("smooth", "VEC3", "frag_offset"),
                   ("smooth", "VEC3", "frag_axis_x"), ("smooth", "VEC3", "frag_axis_y"),
                   ("smooth", "VEC3", "frag_axis_z"), ("flat", "VEC3", "frag_half"), ("flat", "VEC4", "frag_params"),
                   ("flat", "VEC4", "frag_parent_origin"), ("flat", "VEC4", "frag_parent_q"),
                   ("flat", "VEC4", "frag_parent_half"))
# Everything per draw travels in one uniform block (push constants are limited to 128 bytes).
# std140: three mat4 then vec4s, no padding; preview/draw.py packs it (uniform_block_data).
UNIFORM_TYPE = "BoxmarchPreview"
UNIFORM_NAME = "preview"
UNIFORM_STRUCT = """struct BoxmarchPreview {
  mat4 object_to_clip;
  mat4 normal_to_view;
  mat4 frame;
  vec4 eye;
  vec4 march;
  vec4 base_color;
  ivec4 mode;
  vec4 quality;
  vec4 blend;
  vec4 occlusion;
};
"""
FRAGMENT_OUTPUTS = ((0, "VEC4", "frag_color"),)
# The hidden-box pre-pass (docs/PREVIEW.md, "Hidden boxes"): the occluders' nearest window depth,
# which the marching stage reads per pixel, and the occluder index each pre-pass draw pulls the
# box mesh in to.
OCCLUDER_SAMPLER = (0, "FLOAT_2D", "occluder_depth")
OCCLUDER_INDEX = ("FLOAT", "occluder_index")
# The resolved passes (preview/resolve.py): each pixel's nearest hit as the uint bits of its window
# depth, kept by the visibility pass (imageAtomicMin) and read by the shade and resolve passes;
# the full-screen stages' vertex input and the composite's textures.
HIT_MIN_IMAGE = (1, "R32UI", "UINT_2D", "hit_min")
# hit_min's value where no hit was kept: the bits of 2.0, above the bits of every depth kept (in
# [0, 1], as the depth buffer clamps it: a hit at or past the far plane is kept at 1.0, as the
# plain draw keeps it); defined as BM_NO_HIT in the resolved passes' stages.
NO_HIT = 0x40000000
FULLSCREEN_INPUT = ("VEC2", "pos")
COMPOSITE_SAMPLERS = ((0, "FLOAT_2D", "shaded_colour"), (1, "FLOAT_2D", "shaded_depth"))

OUTPUT_MODES = ("SHADED", "NORMAL", "STEPS")

GLSL_TYPES = {"FLOAT": "float", "INT": "int", "VEC2": "vec2", "VEC3": "vec3", "VEC4": "vec4", "MAT4": "mat4"}
# Blender's GL backend spells a create-info depth_write as a gl_FragDepth redeclaration (GLSL 4.20+).
DEPTH_LAYOUTS = {"ANY": "depth_any", "GREATER": "depth_greater", "LESS": "depth_less"}


def gl_declarations(stage: str, layout: str = "CLASSIC", version: str = "330 core",
                    depth_write: str | None = None, resolved: bool = False) -> str:
    """What Blender's GL backend puts before our source from the preview's create-info (stage
    'vert' or 'frag'): uniform block, vertex inputs, stage interface, outputs and, for
    ``depth_write`` (a key of DEPTH_LAYOUTS; None: no declaration, as Blender 3.4), the
    gl_FragDepth layout; ``resolved``: the resolved passes' hit_min image (GLSL 4.30).
    For compilers and drivers outside Blender (tests, bench/bench_gpu_frame.py)."""
    lines = [f"#version {'430 core' if resolved else version}", UNIFORM_STRUCT,
             f"layout(std140) uniform _{UNIFORM_NAME} {{ {UNIFORM_TYPE} {UNIFORM_NAME}; }};"]
    if stage == "vert":
        lines += [f"layout(location = {i}) in {GLSL_TYPES[t]} {name};"
                  for i, (t, name) in enumerate(VERTEX_INPUTS[layout])]
    direction = "out" if stage == "vert" else "in"
    lines += [f"{'flat ' if interp == 'flat' else ''}{direction} {GLSL_TYPES[t]} {name};"
              for interp, t, name in STAGE_INTERFACE]
    if stage == "vert":
        lines.append(f"uniform {GLSL_TYPES[OCCLUDER_INDEX[0]]} {OCCLUDER_INDEX[1]};")
    if stage == "frag":
        lines.append(f"uniform sampler2D {OCCLUDER_SAMPLER[2]};")
        lines += [f"layout(location = {slot}) out {GLSL_TYPES[t]} {name};" for slot, t, name in FRAGMENT_OUTPUTS]
        if resolved:
            lines.append(f"layout(r32ui) uniform uimage2D {HIT_MIN_IMAGE[3]};")
        if depth_write is not None:
            lines.append(f"layout({DEPTH_LAYOUTS[depth_write]}) out float gl_FragDepth;")
    return "\n".join(lines) + "\n"

# map() of each preset; `box_half` is set by the fragment stage (shaders/glsl/sdf.glsl).
PRESET_MAPS = {name: f"float map(vec3 p)\n{{\n  return sdf_preset_{name.lower()}(p, box_half);\n}}\n"
               for name in core.SDF_PRESETS}
# Each box the preset its shape id picks (shaders/glsl/sdf.glsl, bm_sdf_by_id).
PER_BOX = "PER_BOX"
PRESET_MAPS[PER_BOX] = "float map(vec3 p)\n{\n  return bm_sdf_by_id(box_params.x, p, box_half);\n}\n"
# Each box's shape blended into its parent's (bm_sdf_blend_parent), blend radius in box_parent_origin.w.
PER_BOX_BLEND = "PER_BOX_BLEND"
PRESET_MAPS[PER_BOX_BLEND] = ("float map(vec3 p)\n{\n  return bm_sdf_blend_parent(box_params.x, p, box_half, box_parent_origin.xyz, "
                              "box_parent_q, box_parent_half, box_parent_origin.w);\n}\n")

# The maps whose hit the fragment stage solves in closed form instead of marching (raymarch.glsl
# bm_preset_hit, defined as BM_CLOSED_FORM): each preset by its shape id, PER_BOX by each box's;
# PER_BOX_BLEND's fillet and a user's text march.
CLOSED_FORM_SHAPES = {**{name: f"{float(i)}" for i, name in enumerate(core.SDF_PRESETS)}, PER_BOX: "box_params.x"}


def closed_form_define(sdf: str, local_mirror=(1.0, 1.0, 1.0)) -> str:
    """The line defining BM_CLOSED_FORM for preset map ``sdf`` (a key of CLOSED_FORM_SHAPES): its
    hit and normal, the ray seen through an engine's local mirror (as engine_map_source mirrors the
    point) and the normal mirrored back."""
    shape = CLOSED_FORM_SHAPES[sdf]
    if all(float(v) > 0 for v in local_mirror):
        return f"#define BM_CLOSED_FORM bm_preset_hit({shape}, ro, rd, box_half)"
    mirror = "vec3(" + ", ".join(f"{float(v):.1f}" for v in local_mirror) + ")"
    return f"#define BM_CLOSED_FORM (bm_preset_hit({shape}, ro * {mirror}, rd * {mirror}, box_half) * vec4({mirror}, 1.0))"


# User text goes between two #line directives: the compiler then reports errors in it by the
# line number the user sees in the text editor, and anything after it from USER_END_LINE on.
USER_END_LINE = 100000


def user_map_source(text: str) -> str:
    return f"#line 1\n{text}\n#line {USER_END_LINE}\n"


def engine_map_source(body: str, local_mirror) -> str:
    """``body``'s map() as an engine whose object frame is mirrored evaluates it (export preset
    UNITY, docs/EXPORT.md): the box-local point mirrored (Unity: x negated) before the SDF;
    normals follow through the gradient of the wrapped map()."""
    mirror = ", ".join(f"{float(v):.1f}" for v in local_mirror)
    return (f"#define map bm_engine_map\n{body}\n#undef map\n"
            f"float map(vec3 p)\n{{\n  return bm_engine_map(p * vec3({mirror}));\n}}\n")


def fragment_source(sdf: str = "BOX", user_text: str | None = None, local_mirror=(1.0, 1.0, 1.0),
                    resolved: bool = False, eye_boxes: bool = False) -> str:
    """The fragment stage as Blender compiles it (after its own declarations): the library, the
    preset's map() (and its closed-form hit, BM_CLOSED_FORM) or the user's text (seen through an
    engine's local mirror, if any), and the preview's main(); ``resolved``: the stage of the resolved passes (BM_RESOLVED), which writes
    no depth; ``eye_boxes``: the stage drawing the boxes that hold the eye (BM_EYE_BOXES), whose
    marches from the eye write their hit's depth, nearer than the fragment (compiled without the
    depth declaration)."""
    if user_text is None and sdf not in PRESET_MAPS:
        raise ValueError(f"sdf must be one of {tuple(PRESET_MAPS)}, got {sdf!r}")
    body = user_map_source(user_text) if user_text is not None else PRESET_MAPS[sdf]
    if any(float(v) < 0 for v in local_mirror):
        body = engine_map_source(body, local_mirror)
    defines = ["#define BM_RESOLVED", f"#define BM_NO_HIT {NO_HIT}u"] if resolved else []
    if eye_boxes and not resolved:
        defines.append("#define BM_EYE_BOXES")
    if user_text is None and sdf in CLOSED_FORM_SHAPES:
        defines.append(closed_form_define(sdf, local_mirror))
    return "\n".join([*defines, read_glsl("decode.glsl"), read_glsl("sdf.glsl"), read_glsl("box_params.glsl"),
                      read_glsl("raymarch.glsl"), body, read_glsl("preview.frag.glsl")])


def fullscreen_source(stage: str) -> str:
    """A full-screen stage of the resolved passes (shaders/glsl/preview_resolve.glsl): 'vertex',
    'resolve_depth', 'composite' or 'composite_steps'."""
    defines = {"vertex": ["BM_VERTEX"], "resolve_depth": ["BM_RESOLVE_DEPTH"], "composite": ["BM_COMPOSITE"],
               "composite_steps": ["BM_COMPOSITE", "BM_COMPOSITE_STEPS"]}[stage]
    return "\n".join([*(f"#define {name}" for name in defines), f"#define BM_NO_HIT {NO_HIT}u",
                      read_glsl("preview_resolve.glsl")])


def fullscreen_declarations(stage: str) -> str:
    """What Blender's GL backend puts before a full-screen stage of the resolved passes from its
    create-info (preview/shader.py fullscreen_shader): the vertex input, the hit_min image or the
    composite's textures, the colour output. For compilers and drivers outside Blender (tests,
    bench/gl_preview.py)."""
    lines = ["#version 430 core"]
    if stage == "vertex":
        lines.append(f"layout(location = 0) in {GLSL_TYPES[FULLSCREEN_INPUT[0]]} {FULLSCREEN_INPUT[1]};")
    elif stage == "resolve_depth":
        lines.append(f"layout(r32ui) uniform uimage2D {HIT_MIN_IMAGE[3]};")
    else:
        lines += [f"uniform sampler2D {name};" for _slot, _type, name in COMPOSITE_SAMPLERS]
    if stage != "vertex":
        lines += [f"layout(location = {slot}) out {GLSL_TYPES[t]} {name};" for slot, t, name in FRAGMENT_OUTPUTS]
    return "\n".join(lines) + "\n"


def vertex_source(layout: str = "CLASSIC", occluder: bool = False) -> str:
    """The vertex stage as Blender compiles it: ``layout``'s decode (the shipped decode.glsl);
    ``occluder``: the hidden-box pre-pass's, which pulls each box in to its occluder box number
    ``occluder_index`` of its shape (box_params.glsl; raymarch.glsl's bm_pixel_size sizes its
    rounding margin, and the march there needs a map(), which the pre-pass never calls)."""
    if layout not in VERTEX_INPUTS:
        raise ValueError(f"layout must be one of {tuple(VERTEX_INPUTS)}, got {layout!r}")
    shapes = ["#define BM_OCCLUDER_PASS", read_glsl("sdf.glsl"), read_glsl("box_params.glsl"), read_glsl("raymarch.glsl"),
              NO_MAP] if occluder else []
    return "\n".join([f"#define BM_LAYOUT_{layout}", read_glsl("decode.glsl"), *shapes, read_glsl("preview.vert.glsl")])


# The map() of the pre-pass's stages, which include raymarch.glsl for its depth rules but march nothing.
NO_MAP = "float map(vec3 p)\n{\n  return 1.0;\n}\n"

# The pre-pass writes, as each occluder's depth, the limit the marching stage compares with
# (raymarch.glsl bm_occluder_limit: a margin farther), so that the depth test of the resolved
# passes, which compare their faces with that depth before any shader runs, keeps the same
# fragments as the marching stage's own test; never nearer than the face (declared GREATER, as
# the marching stage's depth). A colour output is declared as every create-info has one.
OCCLUDER_FRAGMENT_SOURCE = "\n".join([read_glsl("sdf.glsl"), read_glsl("raymarch.glsl"), NO_MAP, """void main()
{
  gl_FragDepth = max(bm_occluder_limit(gl_FragCoord.z, fwidth(gl_FragCoord.z)), gl_FragCoord.z);
  frag_color = vec4(0.0);
}
"""])

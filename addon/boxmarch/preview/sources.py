"""GLSL sources of the viewport preview and the interface Blender's create-info declares for them.

Blender-free (no ``bpy``), so the shader tests assemble exactly what the add-on compiles.
"""
from __future__ import annotations

from pathlib import Path

from .. import core

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
VERTEX_INPUTS = (("VEC3", "pos"), ("VEC4", "offset_color"), ("VEC4", "quat"), ("VEC3", "half_extents"))
# (interpolation, type, name): the quaternion and half-extents are constant over a submesh.
STAGE_INTERFACE = (("smooth", "VEC3", "obj_pos"), ("smooth", "VEC4", "frag_offset"),
                   ("flat", "VEC4", "frag_quat"), ("flat", "VEC3", "frag_half"))
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
};
"""
FRAGMENT_OUTPUTS = ((0, "VEC4", "frag_color"),)

OUTPUT_MODES = ("SHADED", "NORMAL", "STEPS")

# map() of each preset; `box_half` is set by the fragment stage (shaders/glsl/sdf.glsl).
PRESET_MAPS = {name: f"float map(vec3 p)\n{{\n  return sdf_preset_{name.lower()}(p, box_half);\n}}\n"
               for name in core.SDF_PRESETS}

# User text goes between two #line directives: the compiler then reports errors in it by the
# line number the user sees in the text editor, and anything after it from USER_END_LINE on.
USER_END_LINE = 100000


def user_map_source(text: str) -> str:
    return f"#line 1\n{text}\n#line {USER_END_LINE}\n"


def fragment_source(sdf: str = "BOX", user_text: str | None = None) -> str:
    """The fragment stage as Blender compiles it (after its own declarations): the library, the
    preset's map() or the user's text, and the preview's main()."""
    if user_text is None and sdf not in PRESET_MAPS:
        raise ValueError(f"sdf must be one of {tuple(PRESET_MAPS)}, got {sdf!r}")
    body = user_map_source(user_text) if user_text is not None else PRESET_MAPS[sdf]
    return "\n".join([read_glsl("decode.glsl"), read_glsl("sdf.glsl"), read_glsl("raymarch.glsl"), body,
                      read_glsl("preview.frag.glsl")])


def vertex_source() -> str:
    return read_glsl("preview.vert.glsl")

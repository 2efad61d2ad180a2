"""Compile checks of every shader with glslangValidator (no GPU needed), and the GLSL, HLSL and
C++ forms (generated from the GLSL, tests/test_engine_shaders.py) offering the same functions."""
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from boxmarch import core
from boxmarch.formats import layouts, shader_sources
from tests.helpers.glsl import blender_declarations, compile_glsl, validator

SHADERS = Path(__file__).resolve().parent.parent / "shaders"
# Engine-side helpers without a GLSL twin (Blender reads UV maps by name, and the preview's main()
# is the GLSL form of bm_raymarch).
ENGINE_ONLY = {"bm_uv_by_channel", "bm_quaternion_from_channels", "bm_cube_half_extents", "bm_raymarch",
               "bm_raymarch_in_frame"}


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_vertex_stage_compiles_for_every_layout(tmp_path, layout):
    proc = compile_glsl(tmp_path, f"preview_{layout}", "vert", shader_sources.vertex_source(layout), layout)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_vertex_inputs_are_the_layouts_channels():
    """The preview reads exactly the per-vertex frame channels the export writes (and ch_half where the
    layout has no per-vertex half-extents); the per-box parameter channels are not the frame's."""
    n = 3
    data = layouts.BoxData(quaternions=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), offsets=np.zeros((n, 3)),
                           half_extents=np.ones((n, 3)), index=np.zeros(n, np.int64),
                           classic_rgba=np.ones((n, 4), np.float32), box_half_extents=np.ones((1, 3)))
    for layout in layouts.LAYOUTS:
        written = {"ch_" + name.lower(): values.shape[1] for name, values in layouts.channels(layout, data).items()
                   if name != "TABLE" and name not in layouts.PARAM_CHANNELS[layout]}
        read = {name: int(t[-1]) for t, name in shader_sources.VERTEX_INPUTS[layout]
                if name not in ("pos", "ch_half", "ch_params", "ch_parent_origin", "ch_parent_q", "ch_parent_half")}
        assert read == written, layout


@pytest.mark.parametrize("sdf", [*core.SDF_PRESETS, shader_sources.PER_BOX, shader_sources.PER_BOX_BLEND])
def test_fragment_stage_compiles_for_every_preset(tmp_path, sdf):
    proc = compile_glsl(tmp_path, f"preview_{sdf}", "frag", shader_sources.fragment_source(sdf))
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.parametrize("layout", layouts.LAYOUTS)
def test_stages_link(tmp_path, layout):
    vert = tmp_path / "link.vert"
    frag = tmp_path / "link.frag"
    vert.write_text(blender_declarations("vert", layout) + shader_sources.vertex_source(layout))
    frag.write_text(blender_declarations("frag") + shader_sources.fragment_source("TORUS"))
    proc = subprocess.run([validator(), "-l", str(vert), str(frag)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_every_glsl_file_is_compiled():
    used = (shader_sources.vertex_source() + shader_sources.fragment_source("BOX")
            + shader_sources.fullscreen_source("composite"))
    for path in (SHADERS / "glsl").glob("*.glsl"):
        assert path.read_text() in used, f"{path.name} is not part of the compiled preview"


@pytest.mark.parametrize("stage", ["marching", "vertex", "resolve_depth", "composite", "composite_steps"])
def test_resolved_pass_stages_compile(tmp_path, stage):
    """The resolved passes' stages (preview/resolve.py) under the declarations Blender makes of
    their create-infos: the marching stage with the hit_min image and no gl_FragDepth (so the depth
    test may run first), the full-screen stages with their image or textures."""
    if stage == "marching":
        source = shader_sources.gl_declarations("frag", resolved=True) + shader_sources.fragment_source("LINK", resolved=True)
        assert "gl_FragDepth" not in source.split("#else")[0].split("#ifdef BM_RESOLVED")[-1]
    else:
        source = shader_sources.fullscreen_declarations(stage) + shader_sources.fullscreen_source(stage)
    path = tmp_path / f"{stage}.{'vert' if stage == 'vertex' else 'frag'}"
    path.write_text(source)
    proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_user_text_uses_library_and_errors_report_user_lines(tmp_path):
    good = "float map(vec3 p)\n{\n  return op_smooth_union(sd_sphere(p, min3(box_half)), sd_torus(p, 0.5, 0.1), 0.1);\n}"
    proc = compile_glsl(tmp_path, "user_good", "frag", shader_sources.fragment_source("USER", good))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    bad = "float map(vec3 p)\n{\n  float r = 1.0;\n  return lenght(p) - r;\n}"
    proc = compile_glsl(tmp_path, "user_bad", "frag", shader_sources.fragment_source("USER", bad))
    assert proc.returncode != 0
    assert re.search(r"\b0:4\b.*lenght", proc.stdout), proc.stdout  # line 4 of the user's text


# The example's layouts: the keywords BoxmarchExample.shader's KeywordEnum _Layout defines.
HLSL_LAYOUT_KEYWORDS = {"CLASSIC": [], "UV_FRAME": ["-D_LAYOUT_UV_FRAME"], "NORMAL_FRAME": ["-D_LAYOUT_NORMAL_FRAME"]}


@pytest.mark.parametrize("layout", sorted(HLSL_LAYOUT_KEYWORDS))
@pytest.mark.parametrize("entry", ["vert", "frag"])
def test_hlsl_example_compiles(tmp_path, entry, layout):
    proc = subprocess.run([validator(), "-D", "-V", *HLSL_LAYOUT_KEYWORDS[layout], "-e", entry, "-S", entry,
                           str(SHADERS / "hlsl" / "boxmarch_example.hlsl"), "-o", str(tmp_path / f"{entry}.spv")],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_hlsl_example_keywords_are_the_unity_shader_layouts():
    """Each keyword the example tests is one BoxmarchExample.shader declares, and the layouts are
    the UNITY preset's (a layout added to the preset needs a branch in the example)."""
    from boxmarch.formats import presets

    wrapper = (SHADERS / "hlsl" / "BoxmarchExample.shader").read_text()
    example = (SHADERS / "hlsl" / "boxmarch_example.hlsl").read_text()
    assert set(HLSL_LAYOUT_KEYWORDS) == set(presets.PRESETS["UNITY"].layouts)
    for layout in HLSL_LAYOUT_KEYWORDS:
        assert f"_LAYOUT_{layout}" in wrapper
        assert layout == "CLASSIC" or f"defined(_LAYOUT_{layout})" in example


def test_hlsl_with_a_frame_change_compiles(tmp_path):
    source = ('#define BOXMARCH_FRAME float3x3(-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0)\n'
              '#include "boxmarch_example.hlsl"\n')
    path = tmp_path / "framed.hlsl"
    path.write_text(source)
    proc = subprocess.run([validator(), "-D", "-V", "-e", "frag", "-S", "frag", "-I" + str(SHADERS / "hlsl"), str(path),
                           "-o", str(tmp_path / "framed.spv")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


_FUNCTION = re.compile(r"^(?:static\s+)?(\w+)\s+(\w+)\s*\(([^)]*)\)\s*(?:\{|$)", re.M)
_HLSL_TO_GLSL = {"float2": "vec2", "float3": "vec3", "float4": "vec4", "float3x3": "mat3", "float4x4": "mat4"}


def functions(paths, to_glsl=False):
    """{name: (return type, parameter types)} of top-level function definitions."""
    found = {}
    for path in paths:
        for ret, name, params in _FUNCTION.findall(path.read_text()):
            if ret in {"return", "else", "struct"} or name == "main":
                continue
            types = tuple(p.split()[-2] for p in params.replace("\n", " ").split(",") if p.strip())
            if to_glsl:
                ret = _HLSL_TO_GLSL.get(ret, ret)
                types = tuple(_HLSL_TO_GLSL.get(t, t) for t in types)
            found[name] = (ret, types)
    return found


def test_glsl_and_hlsl_have_the_same_functions():
    glsl = functions([SHADERS / "glsl" / n for n in ("decode.glsl", "sdf.glsl", "raymarch.glsl")])
    hlsl = functions([SHADERS / "hlsl" / n for n in ("boxmarch_decode.hlsl", "boxmarch.hlsl", "boxmarch_sdf.hlsl",
                                                     "boxmarch_march.hlsl", "boxmarch_raymarch.hlsl")],
                     to_glsl=True)
    assert len(glsl) > 30
    assert {k: v for k, v in hlsl.items() if k not in ENGINE_ONLY} == glsl
    assert ENGINE_ONLY <= set(hlsl)


def test_cpp_reference_has_the_sdf_library_and_every_preset():
    glsl = functions([SHADERS / "glsl" / "sdf.glsl"])
    cpp_src = SHADERS.parent / "cpp" / "src"
    library = (cpp_src / "shader_library.h").read_text()
    for name in glsl:
        assert re.search(rf"\b{name}\(", library), f"{name} is not in cpp/src/shader_library.h"
    presets = [n for n in glsl if n.startswith("sdf_preset_")]
    assert [n.replace("sdf_preset_", "").upper() for n in presets] == list(core.SDF_PRESETS)
    switch = (cpp_src / "raymarch.cpp").read_text()
    for name in presets:
        assert re.search(rf"return shader::{name}\(p, h\);", switch), f"raymarch.cpp's switch does not call {name}"


def test_benchmark_baseline_shader_compiles(tmp_path):
    path = tmp_path / "naive.frag"
    path.write_text("\n".join([
        "#version 330 core", "uniform mat4 clip_to_object;", "uniform vec4 march;", "uniform ivec4 sizes;",
        "uniform sampler2D boxes;", "layout(location = 0) out vec4 frag_color;",
        shader_sources.read_glsl("decode.glsl"), shader_sources.read_glsl("sdf.glsl"),
        (SHADERS.parent / "bench" / "naive_fullscreen.frag.glsl").read_text()]))
    proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


# The naming conventions every shader file's header states (docs/ENGINES.md, Shader conventions):
# the prefixes of boxmarch's own names and of the families users' map() texts call, and the few
# names an engine or the user owns.
DOCUMENTED_PREFIXES = ("bm_", "BM_", "BOXMARCH_", "sd_", "op_", "sdf_preset_", "box_")
ALIASES = {"min3": "bm_min3", "max3": "bm_max3"}  # the names map() texts use
OWNED_ELSEWHERE = {
    "map",  # the user's distance function
    "main", "vertex", "fragment",  # entry points: three.js's stages, Godot 3's
    "projectionMatrix", "modelViewMatrix", "normalMatrix", "tangent",  # three.js's names, declared for its stages
    # three.js's names the raw WebGL 2 material declares as its ShaderMaterial's prefix would
    "position", "normal", "skinIndex", "skinWeight", "pc_fragColor", "gl_FragDepth",
    "attribute", "varying", "gl_FragColor", "gl_FragDepthEXT", "texture2D",
    "base_color", "march_epsilon", "max_steps", "quality",  # Godot 3 material parameters, as its inspector shows them
}


def top_level_names(text: str) -> list[str]:
    """Names a GLSL, HLSL or Godot shader text declares at file scope: functions, prototypes,
    variables, uniforms, attributes, varyings, structs and macros (comments aside)."""
    text = re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))
    names = re.findall(r"^\s*#\s*define\s+(\w+)", text, re.M)
    text = re.sub(r"^\s*#[^\n]*", "", text, flags=re.M)
    depth, statement = 0, ""
    for ch in text:
        if depth:
            depth += (ch == "{") - (ch == "}")
        elif ch == "{":
            struct = re.search(r"\bstruct\s+(\w+)", statement)
            names.append(struct.group(1) if struct else re.search(r"(\w+)\s*\(", statement).group(1))
            depth, statement = 1, ""
        elif ch == ";":
            statement = re.sub(r"\blayout\s*\([^)]*\)", "", statement)  # GLSL ES 3.00 qualifiers
            words = statement.split()
            if words and words[0] not in ("shader_type", "render_mode", "precision"):
                if "(" in statement.split("=")[0].split(":")[0]:  # a prototype (after ":", a Godot hint)
                    names.append(re.search(r"(\w+)\s*\(", statement).group(1))
                else:
                    declarators = re.sub(r"\[[^]]*\]", "", statement.split("=")[0].split(":")[0]).split(",")
                    names += [re.findall(r"\w+", part)[-1] for part in declarators]
            statement = ""
        else:
            statement += ch
    return names


def threejs_stages() -> str:
    """The GLSL of the three.js material's own stages (template.js: the varyings, both stages, the raw
    material's headers and the lines around the user's map()), from the JavaScript string literals that make them."""
    template = (SHADERS / "threejs" / "template.js").read_text()
    parts = re.findall(r"^var BOXMARCH_(?:VARYINGS|VERTEX|FRAGMENT|RAW_VERTEX|RAW_FRAGMENT) = \[(.*?)\]\.join",
                       template, re.S | re.M)
    parts.append(re.search(r"^\s*fragmentShader: (.*)$", template, re.M).group(1))
    literals = re.findall(r"'((?:[^'\\]|\\.)*)'", "\n".join(parts))
    return "\n".join(literal.replace("\\n", "\n") for literal in literals)


def engine_shader_texts() -> dict[str, str]:
    """What boxmarch puts into an engine's shader: the shared GLSL library (pasted into the three.js
    material and the Godot 3 shader, translated into the HLSL includes), the hand-written HLSL
    includes a Unity shader includes, the three.js stages and the whole Godot 3 shader. Not the
    Unity example shader (a user's shader, in Unity's names) nor Blender's preview stages."""
    texts = {f"glsl/{name}": (SHADERS / "glsl" / name).read_text()
             for name in ("decode.glsl", "sdf.glsl", "box_params.glsl", "raymarch.glsl")}
    texts.update({f"hlsl/{name}": (SHADERS / "hlsl" / name).read_text()
                  for name in ("boxmarch.hlsl", "boxmarch_raymarch.hlsl")})
    texts["threejs stages"] = threejs_stages()
    texts["godot3/boxmarch.shader"] = (SHADERS / "godot3" / "boxmarch.shader").read_text()
    return texts


def undocumented_names(text: str) -> set[str]:
    return {name for name in top_level_names(text)
            if not name.startswith(DOCUMENTED_PREFIXES) and not re.match(r"bm[A-Z]", name)
            and name not in ALIASES and name not in OWNED_ELSEWHERE}


def test_engine_shader_names_carry_the_documented_prefixes():
    texts = engine_shader_texts()
    names = {where: top_level_names(text) for where, text in texts.items()}
    assert all(len(found) >= 3 for found in names.values()), names  # the parser sees each file's declarations
    assert {"bm_offset_from_color", "box_half", "sd_round_box", "sdf_preset_link", "bmEye", "bmObjPos",
            "bm_hit", "BOXMARCH_FRAME", "bm_v_world_pos", "box_table", "quality"} <= {n for found in names.values() for n in found}
    outside = {where: sorted(undocumented_names(text)) for where, text in texts.items()}
    assert not any(outside.values()), outside


def test_names_check_catches_a_stray_name():
    """Negative control: a helper, a global and a varying without a documented prefix are found."""
    library = (SHADERS / "glsl" / "sdf.glsl").read_text()
    stray = library + "\nfloat min4(vec4 v) { return min(min3(v.xyz), v.w); }\nvec3 half_size = vec3(0.0);\n" \
                      "varying vec3 vNormalLocal;\n"
    assert undocumented_names(stray) == {"min4", "half_size", "vNormalLocal"}


def test_min3_and_max3_are_only_aliases():
    """min3 and max3 stay for users' map() texts and return the bm_ functions, which the library itself calls."""
    library = (SHADERS / "glsl" / "sdf.glsl").read_text()
    for alias, name in ALIASES.items():
        assert f"float {alias}(vec3 v) {{ return {name}(v); }}" in library
    for path in (SHADERS / "glsl").glob("*.glsl"):
        code = re.sub(r"//[^\n]*", "", path.read_text())
        calls = len(re.findall(r"(?<![\w.])(?:min3|max3)\(", code))
        assert calls == (2 if path.name == "sdf.glsl" else 0), path.name  # the two alias definitions

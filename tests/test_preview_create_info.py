"""The create-info the preview builds (boxmarch.preview.shader), recorded through a stub of
Blender's gpu module (tests/helpers/gpu_stub.py), the marching shader's and the hidden-box
pre-pass's: each one's gl_FragDepth declaration is the direction its own fragment source keeps
(GREATER for both: the marched depth is clamped to the face's, the pre-pass writes its
occluders' depth a margin farther; ANY for the stage drawing the boxes that hold the eye, whose
marches from the eye write a depth nearer than the face), and each compiles and links as
Blender's GL backend declares it. Blender-free; the preview's real compile runs in
tests/test_preview_blender.py."""
import re
import subprocess

import pytest

from boxmarch.formats import shader_sources
from tests.helpers import gpu_stub
from tests.helpers.glsl import preprocessed, validator


def depth_direction(fragment: str):
    """The depth_write a fragment's gl_FragDepth writes make true (in the branches its defines
    take): GREATER when every write is max(<depth>, gl_FragCoord.z) (never nearer than the
    rasterised face), LESS when every one is min(<depth>, gl_FragCoord.z), ANY for any other write,
    None when it writes no depth."""
    writes = [re.sub(r"\s+", "", w) for w in re.findall(r"gl_FragDepth\s*=\s*([^;]+);", preprocessed(fragment))]
    if not writes:
        return None
    for direction, function in (("GREATER", "max("), ("LESS", "min(")):
        if all(w.startswith(function) and w.endswith(",gl_FragCoord.z)") for w in writes):
            return direction
    return "ANY"


def create_info_faults(info) -> list:
    """What is wrong with one recorded create-info: a depth declaration other than the one its
    fragment source keeps (ANY forbids the early depth test; the opposite direction is false)."""
    (fragment,) = info.called("fragment_source")
    declared = [d for (d,) in info.called("depth_write")]
    kept = depth_direction(fragment[0])
    wanted = [] if kept is None else [kept]
    return [] if declared == wanted else [f"declares depth_write {declared}, its fragment's writes keep {wanted}"]


def built_create_infos(gpu, depth_write=None, eye_boxes=False):
    """Every create-info the preview builds for each layout under ``gpu``: the marching shader's
    (the BOX preset; ``eye_boxes``: its stage drawing the boxes that hold the eye) and the
    hidden-box pre-pass's, as two lists; with ``depth_write`` set, the preview's DEPTH_WRITE
    (``eye_boxes``: EYE_BOXES_DEPTH_WRITE) replaced by it first (a mutation)."""
    shader = gpu_stub.preview_shader_module(gpu)
    if depth_write is not None:
        setattr(shader, "EYE_BOXES_DEPTH_WRITE" if eye_boxes else "DEPTH_WRITE", depth_write)
    for layout in shader_sources.VERTEX_INPUTS:
        shader.preview_shader("BOX", layout=layout, eye_boxes=eye_boxes)
    marching = list(gpu.built)
    for layout in shader_sources.VERTEX_INPUTS:
        shader.occluder_shader(layout)
    return marching, gpu.built[len(marching):]


def test_preview_declares_the_depth_direction_its_fragment_keeps():
    marching, occluders = built_create_infos(gpu_stub.gpu_module())
    assert len(marching) == len(occluders) == len(shader_sources.VERTEX_INPUTS)
    assert [fault for info in marching + occluders for fault in create_info_faults(info)] == []
    # the preview's clamp, max(...): the marched depth, and the occluders' limit (bm_occluder_limit)
    assert all(info.called("depth_write") == [("GREATER",)] for info in marching + occluders)


def test_the_stage_of_the_eyes_boxes_declares_any_depth():
    """The boxes holding the eye march from it and write a depth nearer than their fragment (the
    far side): that stage declares ANY, which its writes keep; declared GREATER (the others'
    declaration, the negative control) it is caught."""
    eye, _occluders = built_create_infos(gpu_stub.gpu_module(), eye_boxes=True)
    assert len(eye) == len(shader_sources.VERTEX_INPUTS)
    assert [fault for info in eye for fault in create_info_faults(info)] == []
    assert all(info.called("depth_write") == [("ANY",)] for info in eye)
    wrong, _occluders = built_create_infos(gpu_stub.gpu_module(), depth_write="GREATER", eye_boxes=True)
    assert all(create_info_faults(info) for info in wrong)


@pytest.mark.parametrize("wrong", ["ANY", "LESS", "UNCHANGED"])
def test_a_preview_declaring_another_depth_direction_is_caught(wrong):
    """Negative control: the same build with the preview's DEPTH_WRITE changed."""
    marching, _occluders = built_create_infos(gpu_stub.gpu_module(), depth_write=wrong)
    assert all(create_info_faults(info) for info in marching)


def test_a_pre_pass_writing_an_undeclared_depth_is_caught(monkeypatch):
    """Negative control: the pre-pass's fragment made to write its depth, nearer, undeclared."""
    monkeypatch.setattr(shader_sources, "OCCLUDER_FRAGMENT_SOURCE",
                        "void main()\n{\n  frag_color = vec4(0.0);\n  gl_FragDepth = min(0.5, gl_FragCoord.z);\n}\n")
    _marching, occluders = built_create_infos(gpu_stub.gpu_module())
    assert occluders and all(create_info_faults(info) for info in occluders)


def test_preview_on_blender_3_4_builds_without_a_depth_declaration():
    marching, occluders = built_create_infos(gpu_stub.gpu_module(depth_write=False))
    assert len(marching) == len(occluders) == len(shader_sources.VERTEX_INPUTS)
    assert all(info.called("depth_write") == [] for info in marching + occluders)


@pytest.mark.slow  # glslangValidator per layout
def test_the_recorded_create_info_compiles_and_links(tmp_path):
    """Each layout's create-infos (the marching shader's and the pre-pass's), as Blender's GL
    backend declares them, through glslangValidator (-l: the stage interface of the two stages
    must match); without the create-info's declaration of one interface member the marching
    fragment must fail."""
    marching, occluders = built_create_infos(gpu_stub.gpu_module())
    vert, frag = tmp_path / "preview.vert", tmp_path / "preview.frag"
    for info in occluders + marching:
        vert.write_text(info.glsl("vert"))
        frag.write_text(info.glsl("frag"))
        proc = subprocess.run([validator(), "-l", str(vert), str(frag)], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    declared = "flat in vec3 frag_half;\n"
    assert declared in info.glsl("frag")
    frag.write_text(info.glsl("frag").replace(declared, ""))
    proc = subprocess.run([validator(), "-l", str(vert), str(frag)], capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0

"""The march's ranges (max steps, hit epsilon, quality) come from one source,
addon/boxmarch/formats/march_ranges.py: the Blender preview's properties take it, shaders/generate.py
writes it into the three.js material's checks and the Godot 3 shader's hints, and every doc that
states a range states that one (the docs are checked here, not generated)."""
import re

import pytest

from boxmarch.formats.march_ranges import GODOT3_UNIFORMS, MARCH_RANGES, THREEJS_OPTIONS, stated
from tests.engines import threejs
from tests.engines.import_helpers import REPO

# "A to B", "A..B" or "A-B" with numbers A and B: every way the docs have written a range.
RANGE = re.compile(r"(\d[\d.]*(?:e-?\d+)?) ?(?:to|\.\.|-) ?(\d[\d.]*(?:e-?\d+)?)")
# Where each doc states each range: the text right after the anchor (within SPAN characters)
# holds it, the first range there.
SPAN = 160
ANCHORS = {
    "shaders/threejs/README.md": {name: f"| `{option}` |" for name, option in THREEJS_OPTIONS.items()},
    "engines/godot3/README.md": {name: f"`{uniform}` (" for name, uniform in GODOT3_UNIFORMS.items()},
    "docs/ENGINES.md": {"max_steps": "`maxSteps` a whole number from", "epsilon": "`epsilon` from",
                        "quality": "`quality` from"},
    "docs/PREVIEW.md": {"quality": "| `quality` |"},
}


def first_range(text, anchor):
    at = text.find(anchor)
    assert at >= 0, f"no {anchor!r}"
    found = RANGE.search(text[at : at + len(anchor) + SPAN])
    return None if found is None else f"{found.group(1)} to {found.group(2)}"


@pytest.mark.parametrize("doc", sorted(ANCHORS))
def test_every_doc_states_the_sources_ranges(doc):
    text = (REPO / doc).read_text()
    for name, anchor in ANCHORS[doc].items():
        assert first_range(text, anchor) == stated(name), (doc, name, first_range(text, anchor))


def test_a_doc_stating_another_range_is_caught():
    row = "| `quality` | number | `1` | the quality knob, 0.01 to 1: 1 is the full march |"
    assert first_range(row, "| `quality` |") != stated("quality")
    assert first_range("`quality` (0.01-1, default 1)", "`quality` (") == "0.01 to 1"


def test_the_three_js_material_and_the_godot_shader_carry_the_source():
    material = threejs.shipped_material("r111")
    for name, option in THREEJS_OPTIONS.items():
        least, most, whole = MARCH_RANGES[name]
        assert f"  {option}: {{ min: {least!r}, max: {most!r}, whole: {str(whole).lower()} }}" in material
    from boxmarch.formats import shader_sources

    godot = (shader_sources.shader_dir() / "godot3" / "boxmarch.shader").read_text()
    assert "uniform int max_steps : hint_range(1, 512) = 96;" in godot
    assert "uniform float quality : hint_range(0.05, 1.0) = 1.0;" in godot


def test_the_unity_example_shaders_quality_slider_is_the_sources():
    """shaders/hlsl/BoxmarchExample.shader is written by hand (Unity's ShaderLab): checked, not generated."""
    text = (REPO / "shaders" / "hlsl" / "BoxmarchExample.shader").read_text()
    least, most = re.search(r'_Quality \("[^"]*", Range\(([^,]+), ([^)]+)\)\)', text).groups()
    assert (float(least), float(most)) == MARCH_RANGES["quality"][:2]

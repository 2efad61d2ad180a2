"""The ranges of the march's settings, one source for every place that states or checks them:
the Blender preview's properties (properties.py), the three.js material's option checks
(BOXMARCH_OPTION_RANGES, which shaders/generate.py writes into shaders/threejs/) and the Godot 3
shader's uniform hints (also generated); tests/test_march_ranges.py checks that every engine
README and docs/*.md states these ranges. Plain Python with no imports, so that
shaders/generate.py loads it by path without the add-on.

Each entry: (least, most, whole: True for a whole number)."""

MARCH_RANGES = {
    "max_steps": (1, 512, True),      # most SDF evaluations per fragment (the march's loop bound)
    "epsilon": (1e-7, 1.0, False),    # hit distance, box-local units
    "quality": (0.05, 1.0, False),    # the quality knob (shaders/glsl/raymarch.glsl bm_quality)
}

# The names each engine gives them.
THREEJS_OPTIONS = {"max_steps": "maxSteps", "epsilon": "epsilon", "quality": "quality"}
GODOT3_UNIFORMS = {"max_steps": "max_steps", "epsilon": "march_epsilon", "quality": "quality"}


def stated(name: str) -> str:
    """The range as the docs write it: "1 to 512", "1e-7 to 1", "0.05 to 1"."""
    def number(value):
        text = f"{value:g}"
        return text.replace("e-0", "e-")

    least, most, _whole = MARCH_RANGES[name]
    return f"{number(least)} to {number(most)}"

"""bench/vk_early_depth (the Vulkan early-depth harness) built by its build.sh and run on Mesa
lavapipe, the Vulkan driver on the CPU that scripts/setup.sh installs, at a small size: what its
figures must be whatever the driver culls, checked against what is known without the harness.

* Every layer's fragments run back to front (a full-screen triangle per layer), so at least
  L x W x H invocations are counted there, and no variant in any order counts more than L layers
  per pixel plus lavapipe's slack: it counts whole 4 x 4 blocks where some are partly covered
  (measured: 1.0625 layers per layer at 64 x 64, one extra block per column of blocks), bounded
  here by one block per block row and per block column.
* The read-back picture is the front layer's: red names the layer, green is the shader's hash
  sum, recomputed here from the GLSL's definition; behind the cleared depth nothing is drawn.
* The depth written lies a quarter to a half of a layer gap behind the face (0 where the shader
  writes none, writes the face's own depth, or runs under early_fragment_tests, whose depth write
  the Vulkan specification says has no effect).
* The Khronos validation layer (core, synchronization and best-practice checks) reports nothing
  about the harness's use of Vulkan.
* Each variant's SPIR-V declares its depth execution modes (spirv-dis, not the harness's reader),
  and a module with the wrong ones, a missing shader, an unknown device or a bad option stops the
  harness with one line and no JSON.

What lavapipe itself does (reported, not asserted): it counts the same invocations in every
variant and order (4.25 per pixel here, hidden fragments included: its counter runs before its
own early test), but its time shows the early test: behind the cleared depth no_depth_write and
early_fragment_tests take about 0.2x their back-to-front time, the depth-writing variants,
depth_greater included, about 0.9x."""
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # builds the harness (g++) and runs it on lavapipe

ROOT = Path(__file__).resolve().parent.parent
HARNESS = ROOT / "bench" / "vk_early_depth"
LAVAPIPE_ICD = Path("/usr/share/vulkan/icd.d/lvp_icd.x86_64.json")
WIDTH, HEIGHT, LAYERS, ITERATIONS = 64, 64, 4, 16
VARIANTS = ["no_depth_write", "depth_undeclared", "depth_greater", "depth_unchanged", "early_fragment_tests"]
ORDERS = ["front_to_back", "back_to_front", "behind_cleared_depth"]
# The depth-related execution modes the GLSL of each variant asks for (layer.frag.glsl).
EXPECTED_MODES = {"no_depth_write": set(), "depth_undeclared": {"DepthReplacing"},
                  "depth_greater": {"DepthReplacing", "DepthGreater"},
                  "depth_unchanged": {"DepthReplacing", "DepthUnchanged"},
                  "early_fragment_tests": {"EarlyFragmentTests", "DepthReplacing"}}


def lavapipe_environment():
    need(None if LAVAPIPE_ICD.exists() else f"{LAVAPIPE_ICD} is missing (apt-get install mesa-vulkan-drivers)")
    return dict(os.environ, VK_DRIVER_FILES=str(LAVAPIPE_ICD), VK_ICD_FILENAMES=str(LAVAPIPE_ICD))


def run_harness(binary, *arguments):
    return subprocess.run([str(binary), "--device", "llvmpipe", "--size", f"{WIDTH}x{HEIGHT}", "--layers",
                           str(LAYERS), "--iterations", str(ITERATIONS), "--max-frames", "3", *arguments],
                          env=lavapipe_environment(), capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    for tool in ("g++", "glslangValidator", "spirv-dis"):
        need(None if shutil.which(tool) else f"{tool} is missing (apt-get install g++ glslang-tools)")
    need(None if Path("/usr/include/vulkan/vulkan.h").exists() else "the Vulkan headers are missing "
         "(apt-get install libvulkan-dev)")
    out = tmp_path_factory.mktemp("vk_early_depth")
    proc = subprocess.run(["bash", str(HARNESS / "build.sh"), str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def measured(built, tmp_path_factory):
    """The harness's JSON (parsed strictly: NaN or Infinity would fail) and its read-back images."""
    images = tmp_path_factory.mktemp("images")
    json_path = images / "figures.json"
    proc = run_harness(built / "vk_early_depth", "--json", str(json_path), "--images", str(images))
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]

    def refuse(token):
        raise ValueError(f"non-strict JSON token {token}")

    figures = json.loads(json_path.read_text(), parse_constant=refuse)
    return {(r["variant"], r["order"]): r for r in figures["results"]}, figures, images


def read_ppm(path):
    data = path.read_bytes()
    header = data.split(b"\n", 3)
    assert header[0] == b"P6" and header[1] == f"{WIDTH} {HEIGHT}".encode() and header[2] == b"255"
    return np.frombuffer(header[3], dtype=np.uint8).reshape(HEIGHT, WIDTH, 3)


def hash_shade(layer):
    """layer.frag.glsl's work() for every pixel of ``layer``: the sum of ``ITERATIONS`` hash words'
    top 10 bits over its largest value (exact integers, as the float sum is)."""
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH].astype(np.uint32)
    state = x * np.uint32(1973) + y * np.uint32(9277) + np.uint32(layer * 26699)
    total = np.zeros((HEIGHT, WIDTH), dtype=np.int64)
    for _ in range(ITERATIONS):
        state = state * np.uint32(747796405) + np.uint32(2891336453)
        word = ((state >> np.uint32(16)) ^ state) * np.uint32(277803737)
        total += word >> np.uint32(22)
    return total / (1023.0 * ITERATIONS)


def pixels_not_of_layer(image, layer):
    """Pixels whose red does not name ``layer`` or whose green is not its hash shade (one 8-bit step
    of rounding allowed)."""
    green = np.rint(hash_shade(layer) * 255.0)
    return int(np.count_nonzero((image[..., 0] != layer + 1) | (np.abs(image[..., 1] - green) > 1)))


def test_every_layer_runs_back_to_front_and_no_variant_counts_more(measured):
    results, figures, _ = measured
    assert figures["pipeline_statistics"] is True and figures["device"]["name"].startswith("llvmpipe")
    slack = 16 * (WIDTH // 4 + HEIGHT // 4) / (WIDTH * HEIGHT)  # one 4 x 4 block per block row and column
    for variant in VARIANTS:
        assert results[variant, "back_to_front"]["invocations_per_pixel"] >= LAYERS, variant
        for order in ORDERS:
            assert results[variant, order]["invocations_per_pixel"] <= LAYERS * (1 + slack), (variant, order)


def test_the_front_layer_wins_and_nothing_shows_behind_the_cleared_depth(measured):
    results, _, images = measured
    for variant in VARIANTS:
        for order in ("front_to_back", "back_to_front"):
            image = read_ppm(images / f"{variant}_{order}.ppm")
            assert pixels_not_of_layer(image, 0) == 0, (variant, order)
            assert results[variant, order]["wrong_pixels"] == 0
        hidden = read_ppm(images / f"{variant}_behind_cleared_depth.ppm")
        assert not hidden.any(), variant
    # Negative control: the second layer's colours are not what the pictures show.
    assert pixels_not_of_layer(read_ppm(images / "depth_greater_front_to_back.ppm"), 1) > 0.9 * WIDTH * HEIGHT


def test_depth_written_behind_the_face(measured):
    results, _, _ = measured
    offset = float(np.mean(0.25 + 0.25 * hash_shade(0)))  # layer.frag.glsl: in gaps between layers
    expected = {"no_depth_write": 0.0, "depth_undeclared": offset, "depth_greater": offset, "depth_unchanged": 0.0,
                "early_fragment_tests": 0.0}
    for variant, depth in expected.items():
        for order in ORDERS:
            written = results[variant, order]["depth_above_face_in_layer_gaps"]
            assert abs(written - (0.0 if order == "behind_cleared_depth" else depth)) < 1e-4, (variant, order)
    assert 0.3 < offset < 0.45  # the check above tells a write from none


def test_the_validation_layer_reports_nothing(built, tmp_path):
    layer = Path("/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json")
    need(None if layer.exists() else "the Khronos validation layer is missing (apt-get install vulkan-validationlayers)")
    checks = ["VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT", "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT"]
    proc = subprocess.run([str(built / "vk_early_depth"), "--device", "llvmpipe", "--size", "32x32", "--layers", "2",
                           "--iterations", "4", "--max-frames", "1", "--json", str(tmp_path / "figures.json")],
                          env=dict(lavapipe_environment(), VK_INSTANCE_LAYERS="VK_LAYER_KHRONOS_validation",
                                   VK_LAYER_ENABLES=":".join(checks), VK_LOADER_DEBUG="layer"),
                          capture_output=True, text=True, timeout=120)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output[-3000:]
    # The loader's own log shows the layer in place, so silence means it checked and found nothing.
    assert 'Insert instance layer "VK_LAYER_KHRONOS_validation"' in output
    assert re.findall(r".*Validation (?:Error|Warning|Performance Warning).*", output) == []


def test_spirv_declares_each_variants_depth_modes(built, measured):
    results, _, _ = measured
    for variant, modes in EXPECTED_MODES.items():
        listing = subprocess.run(["spirv-dis", str(built / f"{variant}.frag.spv")], capture_output=True, text=True,
                                 check=True).stdout
        declared = {line.split()[-1] for line in listing.splitlines() if "OpExecutionMode" in line} - {"OriginUpperLeft"}
        assert declared == modes, variant
        assert set(results[variant, "front_to_back"]["execution_modes"].split()) - {"none"} == modes


@pytest.mark.parametrize("case", ["missing shader", "wrong modes", "unknown device", "bad option"])
def test_failures_stop_with_one_line_and_no_json(built, tmp_path, case):
    shaders = tmp_path / "shaders"
    shutil.copytree(built, shaders)
    arguments, expected = [], {"missing shader": "shader not found", "wrong modes": "declares DepthReplacing, not",
                               "unknown device": "no Vulkan device matches", "bad option": "--layers must be"}[case]
    if case == "missing shader":
        (shaders / "depth_greater.frag.spv").unlink()
    elif case == "wrong modes":  # the undeclared module under the declared variant's name
        shutil.copy(shaders / "depth_undeclared.frag.spv", shaders / "depth_greater.frag.spv")
    elif case == "unknown device":
        arguments = ["--device", "no such device"]
    else:
        arguments = ["--layers", "0"]
    json_path = tmp_path / "figures.json"
    proc = run_harness(shaders / "vk_early_depth", *arguments, "--json", str(json_path))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("vk_early_depth: ") and expected in proc.stderr
    assert list(tmp_path.glob("figures.json*")) == []

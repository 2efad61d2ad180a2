"""The GPU cost model of the CPU reference (core.render_boxes' cost counts, draw order, early depth,
quality knob) on scenes whose counts are worked out by hand, and the preview's octant orders."""
import re
import subprocess

import numpy as np
import pytest

from boxmarch import core, scenes
from boxmarch.preview import mesh_data
from boxmarch.formats import shader_sources
from tests.engines import perspective
from tests.helpers.preview_render import quaternions_of
from tests.helpers.tools import need

SHADERS = shader_sources.shader_dir()

SIZE = 8  # pixels; the orthographic view below maps x, y in [-1, 1] onto them: pixel centres at
# -0.875, -0.625, ..., 0.875 (0.25 apart)


def orthographic():
    """Looks down -z from z = 0; window depth = (-z - 0.1) / 9.9 for z in [-10, -0.1]."""
    near, far = 0.1, 10.0
    m = np.eye(4)
    m[2, 2], m[2, 3] = -2 / (far - near), -(far + near) / (far - near)
    return m


def render(origins, half, sdf="BOX", **plan):
    n = len(origins)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    return core.render_boxes(origins, q, half, orthographic(), np.eye(4), SIZE, SIZE, sdf=sdf, **plan)


# Box A: half 0.5 at z = -2 covers the 4 x 4 pixel centres with |x|, |y| < 0.5 (16 fragments);
# box B: half 1 at z = -4 covers all 8 x 8 (64). A BOX hit is at the face where the march starts:
# 1 step, plus 3 normal taps (forward differences from the hit's own distance) = 4 map() calls per
# fragment.
A_THEN_B = ([[0.0, 0.0, -2.0], [0.0, 0.0, -4.0]], [[0.5, 0.5, 0.5], [1.0, 1.0, 0.5]])


def test_counts_of_two_overlapping_boxes_without_early_depth():
    cost = render(*A_THEN_B).cost
    assert cost == {"fragments": 80, "marched_fragments": 80, "occluded_fragments": 0, "lod_fragments": 0, "sdf_evaluations": 320,
                    "hidden_fragments": 16, "hidden_evaluations": 64, "covered_pixels": 64}


def test_early_depth_front_first_skips_the_hidden_marches():
    result = render(*A_THEN_B, early_depth=True)
    assert result.cost == {"fragments": 80, "marched_fragments": 64, "occluded_fragments": 0, "lod_fragments": 0, "sdf_evaluations": 256,
                           "hidden_fragments": 0, "hidden_evaluations": 0, "covered_pixels": 64}
    # the image is the one without early depth: A's face at z = -1.5 over B's at z = -3.5
    assert np.array_equal(result.depth, render(*A_THEN_B).depth)
    window = lambda z: (-z - 0.1) / 9.9  # noqa: E731
    assert result.depth[3, 3] == pytest.approx(window(-1.5), abs=1e-6)
    assert result.depth[0, 0] == pytest.approx(window(-3.5), abs=1e-6)


def test_early_depth_back_to_front_saves_nothing():
    result = render(*A_THEN_B, early_depth=True, order=[1, 0])
    assert result.cost["marched_fragments"] == 80
    assert result.cost["hidden_fragments"] == 16 and result.cost["hidden_evaluations"] == 64
    assert np.array_equal(result.depth, render(*A_THEN_B).depth)


def test_occluders_return_hidden_fragments_before_the_march_in_either_order():
    # A's occluder is A itself shrunk by 1/1000 of 0.5 (its face at z = -1.5005), in front of B's
    # face at -3.5 on A's 16 pixels: B's fragments there return before marching, whichever box is
    # drawn first; every fragment still runs (80), the picture is the one without occluders.
    full = render(*A_THEN_B)
    for order in (None, [1, 0]):
        result = render(*A_THEN_B, occluders=True, order=order)
        assert result.cost == {"fragments": 80, "marched_fragments": 64, "occluded_fragments": 16, "lod_fragments": 0,
                               "sdf_evaluations": 256, "hidden_fragments": 0, "hidden_evaluations": 0,
                               "covered_pixels": 64}
        assert np.array_equal(result.depth, full.depth) and np.array_equal(result.rgba, full.rgba)


def test_occluders_end_a_march_at_their_depth():
    # P: a sphere of radius 0.5 at z = -4 in a box reaching z = -1 (pixel centres |x|, |y| <= 0.375);
    # Q: a sphere of radius 1.1 at z = -3 whose first occluder box 1.1 (0.825, 0.4, 0.4), less 0.0011
    # and the eighth of a pixel (0.03125) of bm_occluder_rounding, covers the pixel (0.375, 0.375)
    # from z = -2.126. There P's ray misses its sphere (0.53 from the axis) and would march on
    # towards z = -7; its first step (the distance 2.546 from z = -1) passes the occluder's depth,
    # so with occluders P spends one map() there. Q hits as before.
    p_box = ([[0.0, 0.0, -4.0]], [[0.5, 0.5, 3.0]])
    q_box = ([[0.0, 0.0, -3.0]], [[1.1, 1.1, 1.1]])
    both = (p_box[0] + q_box[0], p_box[1] + q_box[1])
    row, column = 2, 5  # pixel centre (0.375, 0.375): rows run from the top
    p_alone, q_alone = render(*p_box, sdf="SPHERE"), render(*q_box, sdf="SPHERE")
    full = render(*both, sdf="SPHERE")
    assert full.steps[row, column] == p_alone.steps[row, column] + q_alone.steps[row, column]
    assert p_alone.steps[row, column] > 1
    bounded = render(*both, sdf="SPHERE", occluders=True)
    assert bounded.steps[row, column] == q_alone.steps[row, column] + 1
    assert bounded.cost["sdf_evaluations"] < full.cost["sdf_evaluations"]
    assert np.array_equal(bounded.depth, full.depth) and np.array_equal(bounded.rgba, full.rgba)


def test_an_eye_inside_a_shape_sees_that_shape_alone():
    # The eye (origin, looking down -z, 120 degrees) inside sphere E (radius 2 about (1.2, 1.2, -1)),
    # so inside its box too; sphere F (radius 0.1) lies inside E, in view. E's march starts at the
    # eye, inside the shape, and hits at once: E covers its box's whole silhouette at the near
    # plane's depth and hides F. Before E wrote its hit's own depth (it wrote its box's far side's,
    # clamped as the shaders' declared depth_greater required), F showed through E. With the
    # pre-pass (E draws no occluders: the near plane cuts its box) the picture is the same.
    projection = perspective({"fov": 120.0, "near": 0.1, "far": 100.0}, 1.0)
    origins, half = [[1.2, 1.2, -1.0], [0.45, 1.2, -1.5]], [[2.0, 2.0, 2.0], [0.1, 0.1, 0.1]]
    q = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))

    def draw(boxes, **plan):
        return core.render_boxes(np.take(origins, boxes, axis=0), q[boxes], np.take(half, boxes, axis=0), projection,
                                 np.eye(4), 48, 48, sdf="SPHERE", **plan)

    full, f_alone = draw([0, 1]), draw([1])
    f_shown = f_alone.depth < 1.0
    assert f_shown.sum() >= 4  # F is in view: were E's depth its far side's, F would show here
    assert np.all(full.depth[f_shown] < f_alone.depth[f_shown])
    assert np.array_equal(draw([0, 1], occluders=True).depth, full.depth)


@pytest.mark.parametrize("sdf", ["BOX", "CAPSULE"])
def test_the_pre_pass_changes_no_pixel_of_a_pile_far_from_the_object_origin(sdf):
    """Issue 36 item 3 in the CPU reference: 300 boxes 7,300 units from the object's origin, seen
    from 100 units with a near plane of 0.1. A point's clip z and w there are sums of terms of
    thousands that cancel to about 100, so float32 moves its window depth by far more than
    bm_occluder_limit's margin; occluder_depths pushes each occluder back by bm_depth_rounding, as
    the pre-pass's vertex stage does (without it the pre-pass changed 486 of the BOX pile's 3,151
    covered pixels and 6 of the CAPSULE pile's). The picture with the pre-pass is the one without,
    and the pre-pass still skips marches (10,552 and 5,940 fragments)."""
    rng = np.random.default_rng(18)
    n = 300
    origin = np.array([5000.0, -4000.0, 3500.0])
    centres = origin + rng.uniform(-5.0, 5.0, (n, 3))
    quaternions = quaternions_of(scenes.random_rotations(n, rng))
    half = rng.uniform(0.25, 1.5, (n, 3))
    eye = origin + [0.0, -100.0, 30.0]
    forward = (origin - eye) / np.linalg.norm(origin - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, np.cross(right, forward), -forward])
    view[:3, 3] = -view[:3, :3] @ eye
    projection = perspective({"fov": 8.0, "near": 0.1, "far": 300.0}, 1.0)

    def draw(**plan):
        return core.render_boxes(centres, quaternions, half, projection @ view, view, 64, 64, sdf=sdf,
                                 max_steps=128, epsilon=1e-4, **plan)

    plain, cut = draw(), draw(occluders=True)
    assert (plain.depth < 1.0).sum() > 1000 and cut.cost["occluded_fragments"] > 100
    changed = np.any(plain.rgba != cut.rgba, axis=-1) | (plain.depth != cut.depth)
    assert not changed.any(), f"{changed.sum()} pixels changed"


def test_front_to_back_orders_by_distance_or_direction():
    origins = [[0, 0, -1], [0, 0, -5], [0, 0, -3]]
    assert core.front_to_back(origins, [0, 0, 0, 1]).tolist() == [0, 2, 1]
    assert core.front_to_back(origins, [0, 0, 1, 0]).tolist() == [1, 2, 0]  # looking up +z
    assert render(*A_THEN_B, early_depth=True, order=core.front_to_back(A_THEN_B[0], [0, 0, 0, 1])).cost[
        "marched_fragments"] == 64


def test_one_tap_for_a_box_under_the_quality_threshold():
    # A sphere of radius min(h) = 0.1 at the pixel centre (0.125, 0.125), in a box 0.6 deep: 2.4
    # pixels (2 * max(h) / 0.25), under bm_quality(0.25)'s 3. Its box covers that one pixel centre.
    # One tap: one map() where the ray passes the centre (-0.1 < half a pixel: a hit, at the
    # centre's depth), then 3 normal taps. The full march: 0.2 from the face to the sphere, 2 steps.
    box = ([[0.125, 0.125, -2.0]], [[0.1, 0.1, 0.3]])
    low = render(*box, sdf="SPHERE", quality=0.25)
    assert low.cost == {"fragments": 1, "marched_fragments": 1, "occluded_fragments": 0, "lod_fragments": 1, "sdf_evaluations": 4,
                        "hidden_fragments": 0, "hidden_evaluations": 0, "covered_pixels": 1}
    assert low.depth[3, 4] == pytest.approx((2.0 - 0.1) / 9.9, abs=1e-6)
    full = render(*box, sdf="SPHERE", quality=0.5)
    assert full.cost["lod_fragments"] == 0 and full.cost["sdf_evaluations"] == 5
    assert full.depth[3, 4] == pytest.approx((1.9 - 0.1) / 9.9, abs=1e-5)


def test_quality_one_is_the_full_march_and_lower_costs_less():
    rng = np.random.default_rng(3)
    origins = np.column_stack([rng.uniform(-1, 1, (40, 2)), rng.uniform(-9, -1, 40)])
    half = rng.uniform(0.02, 0.3, (40, 3))
    full = render(origins, half, sdf="TORUS")
    same = render(origins, half, sdf="TORUS", quality=1.0, early_depth=True,
                  order=core.front_to_back(origins, [0, 0, 0, 1]))
    assert np.array_equal(full.rgba, same.rgba) and np.array_equal(full.depth, same.depth)
    low = render(origins, half, sdf="TORUS", quality=0.25)
    assert low.cost["sdf_evaluations"] < full.cost["sdf_evaluations"]


def test_normal_rules_cost_three_four_and_six_taps_a_hit():
    for rule, taps in (("FORWARD", 3), ("TETRAHEDRAL", 4), ("CENTRAL", 6)):  # 80 one-step hits (above)
        assert render(*A_THEN_B, normal=rule).cost["sdf_evaluations"] == 80 * (1 + taps)


def test_forward_normal_of_a_sphere_is_its_radius_direction():
    """The shaders' normal (raymarch's is theirs) against the sphere's true one, the hit's direction
    from the centre: a twentieth of a degree typically, a fifth at worst."""
    rng = np.random.default_rng(5)
    half = np.array([0.3, 0.3, 0.3])
    eyes = rng.normal(size=(2000, 3)) * 2.0
    result = core.raymarch(eyes, rng.uniform(-0.2, 0.2, (2000, 3)) - eyes, half, sdf="SPHERE", epsilon=1e-4)
    hit = result.hit.astype(bool)
    assert hit.sum() > 1500
    normals, truth = result.normals[hit].astype(np.float64), result.positions[hit].astype(np.float64)
    angle = np.arctan2(np.linalg.norm(np.cross(normals, truth), axis=1), np.einsum("ij,ij->i", normals, truth))
    assert np.degrees(np.median(angle)) < 0.05 and np.degrees(angle.max()) < 0.2  # float rounding at the taps


def chain_of_links(count=3):
    """A chain along x (LINK boxes 0.46 x 0.23 x 0.06, 0.36 apart, each turned 90 degrees about x
    from the last) and a view 5 units away turned 37 degrees about x: (origins, quaternions,
    half-extents, object_to_view, view direction in object space)."""
    origins = np.column_stack([0.36 * (np.arange(count) - (count - 1) / 2), np.zeros((count, 2))])
    turn = [np.sin(np.pi / 4), 0.0, 0.0, np.cos(np.pi / 4)]
    quaternions = np.where((np.arange(count) % 2 == 0)[:, None], [0.0, 0.0, 0.0, 1.0], turn)
    view = np.eye(4)
    view[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.8, -0.6], [0.0, 0.6, 0.8]]
    view[2, 3] = -5.0
    return origins, quaternions, np.tile([0.23, 0.115, 0.03], (count, 1)), view, -view[2, :3]


def pixels_changed(result, reference):
    """Share of the pixels covered in either image whose coverage differs or whose colour moves by
    more than 1/255 in a channel (bench_gpu_cost.py's measure)."""
    a, b = result.depth < 1, reference.depth < 1
    colour = np.abs(result.rgba[..., :3] - reference.rgba[..., :3]).max(-1) > 1 / 255
    return ((a != b) | (a & b & colour)).sum() / max((a | b).sum(), 1)


def test_forward_normal_changes_under_half_a_percent_of_a_chain_against_central_differences():
    origins, quaternions, half, view, direction = chain_of_links()

    def chain(**plan):
        zoom = np.diag([1.6, 1.6, 1.0, 1.0])  # the view's 2 x 2 window onto 1.25 x 1.25 units
        return core.render_boxes(origins, quaternions, half, orthographic() @ zoom @ view, view, 96, 96, sdf="LINK",
                                 **plan)

    reference = chain(normal="CENTRAL")
    assert (reference.depth < 1).sum() > 800  # the three links cover a tenth of the image
    forward = chain(early_depth=True, order=core.front_to_back(origins, np.append(direction, 0.0)))
    assert pixels_changed(forward, reference) <= 0.005
    # negative control: the tetrahedral taps at max(epsilon, h / 1000) move the shading visibly
    assert pixels_changed(chain(normal="TETRAHEDRAL"), reference) > 0.05


@pytest.mark.parametrize("plan, message", [({"quality": 0.0}, "quality"), ({"quality": 1.5}, "quality"),
                                           ({"order": [0, 0]}, "order"), ({"order": [0, 2]}, "order"),
                                           ({"order": [0]}, "order"), ({"normal": "SOBEL"}, "normal")])
def test_bad_plans_are_refused_and_change_nothing(plan, message):
    depth = np.full((SIZE, SIZE), 0.5, np.float32)
    with pytest.raises(ValueError, match=message):
        core.render_boxes(*A_THEN_B[:1], np.tile([0.0, 0, 0, 1], (2, 1)), A_THEN_B[1], orthographic(), np.eye(4),
                          SIZE, SIZE, depth=depth, **plan)
    assert (depth == 0.5).all()


def baked_boxes(xs):
    """A BakedMesh of one two-triangle quad per box, boxes centred at x = xs."""
    count = len(xs)
    triangles = (np.arange(count)[:, None, None] * 4 + np.array([[0, 1, 2], [0, 2, 3]])).reshape(-1, 3)
    zeros = np.zeros((4 * count, 3), np.float32)
    return mesh_data.BakedMesh(positions=zeros, offsets=np.zeros((4 * count, 4), np.float32),
                               quaternions=np.zeros((4 * count, 4), np.float32), half_extents=zeros,
                               triangles=triangles.astype(np.int32), edges=np.zeros((0, 2), np.int32),
                               origins=np.column_stack([xs, np.zeros(count), np.zeros(count)]).astype(np.float32),
                               box_quaternions=np.zeros((count, 4), np.float32), box_half_extents=np.zeros((count, 3)),
                               submesh_of_vertex=np.repeat(np.arange(count), 4).astype(np.int32))


def test_octant_orders_draw_the_boxes_nearest_the_camera_first():
    baked = baked_boxes([5.0, 0.0, 10.0])
    view = np.eye(4)
    view[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]  # the camera looks along +x (row 2: -forward)
    octant = mesh_data.view_octant(view)
    assert octant & 1
    boxes = mesh_data.octant_triangles(baked, octant)[::2, 0] // 4
    assert boxes.tolist() == [1, 0, 2]
    assert mesh_data.octant_triangles(baked, octant ^ 1)[::2, 0].tolist() == [8, 0, 4]  # looking along -x


def test_preview_fragment_compiles_with_the_depth_greater_declaration(tmp_path):
    """What Blender 4+'s create-info depth_write('GREATER') puts before the source (GLSL 4.20+)."""
    from tests.helpers.glsl import blender_declarations, validator

    declared = blender_declarations("frag", version="450 core", depth_write="GREATER")
    path = tmp_path / "preview.frag"
    for sdf in ("LINK", "SPHERE"):
        path.write_text(declared + shader_sources.fragment_source(sdf))
        proc = subprocess.run([validator(), str(path)], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr


def spirv_depth_modes(tmp_path, hlsl_path, defines=()):
    from tests.helpers.glsl import validator

    proc = subprocess.run([validator(), "-D", "-V", "-H", *defines, "-I" + str(SHADERS / "hlsl"), "-e", "frag", "-S",
                           "frag", str(hlsl_path), "-o", str(tmp_path / "frag.spv")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return set(re.findall(r"ExecutionMode \d+ (Depth\w+)", proc.stdout))


def test_hlsl_example_declares_its_depth_direction(tmp_path):
    example = SHADERS / "hlsl" / "boxmarch_example.hlsl"
    assert spirv_depth_modes(tmp_path, example) == {"DepthReplacing", "DepthGreater"}
    assert spirv_depth_modes(tmp_path, example, ["-DUNITY_REVERSED_Z"]) == {"DepthReplacing", "DepthLess"}
    # negative control: the plain SV_Depth of an undeclared write gives neither direction
    undeclared = tmp_path / "undeclared.hlsl"
    undeclared.write_text(example.read_text().replace(": BM_CONSERVATIVE_DEPTH)", ": SV_Depth)"))
    assert spirv_depth_modes(tmp_path, undeclared) == {"DepthReplacing"}


_CONSERVATIVE_DEPTH_JOB = """function () {
  var gl = document.createElement('canvas').getContext('webgl2');
  var extension = gl.getExtension('EXT_conservative_depth');
  var body = 'layout(depth_greater) out highp float gl_FragDepth;\\nout highp vec4 colour;\\n' +
             'void main() { gl_FragDepth = max(0.75, gl_FragCoord.z); colour = vec4(1.0); }\\n';
  function compile(source) {
    var s = gl.createShader(gl.FRAGMENT_SHADER);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    return gl.getShaderParameter(s, gl.COMPILE_STATUS) ? 'ok' : gl.getShaderInfoLog(s);
  }
  var extension_line = '#extension GL_EXT_conservative_depth : enable\\n';
  var precision = 'precision highp float;\\n';
  return {extension: !!extension,
          first: compile('#version 300 es\\n' + extension_line + precision + body),
          after_precision: compile('#version 300 es\\n' + precision + extension_line + body)};
}"""


@pytest.mark.slow
def test_webgl2_conservative_depth_needs_its_extension_line_first():
    """What docs/ENGINES.md says of three.js: WebGL 2 (ANGLE on SwiftShader) takes depth_greater
    when the #extension line comes before any other token, and refuses it after a precision
    statement, where three.js's ShaderMaterial puts its own."""
    from tests.engines import threejs

    need(threejs.available())
    result = threejs.run_page(b"", _CONSERVATIVE_DEPTH_JOB)
    assert result["extension"] is True
    assert result["first"] == "ok", result["first"]
    assert "before any non-preprocessor tokens" in result["after_precision"], result["after_precision"]


def test_closed_outward_accepts_only_closed_boxes_wound_outward():
    # The preview culls back faces only for such meshes (preview/draw.py CULL_BACK_FACES).
    from boxmarch import scenes

    rng = np.random.default_rng(2)
    positions, _edges, face_starts, _sizes, corner_verts = scenes.box_arrays(
        rng.uniform(-5, 5, (4, 3)), rng.uniform(0.2, 1.0, (4, 3)), scenes.random_rotations(4, rng))
    quads = corner_verts.reshape(-1, 4)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    box = np.repeat(np.arange(4), 8)
    origins = np.array([positions[box == b].mean(axis=0) for b in range(4)])
    assert mesh_data.closed_outward(positions, triangles, origins, box)
    assert not mesh_data.closed_outward(positions, triangles[:, ::-1], origins, box)  # wound inward
    assert not mesh_data.closed_outward(positions, triangles[1:], origins, box)  # one triangle missing: open
    one_inward = triangles.copy()
    turned = box[triangles[:, 0]] == 2
    one_inward[turned] = triangles[turned][:, ::-1]
    assert not mesh_data.closed_outward(positions, one_inward, origins, box)
    # 511 units out the boxes stay culled; made 1e-4 of their size there (under CULL_MIN_STEPS float32
    # steps across: their facing and box-local ray may disagree, cut battery seed 940) they are not
    far = np.array([511.0, 0.0, 0.0])
    assert mesh_data.closed_outward((positions + far).astype(np.float32), triangles, origins + far, box)
    tiny = (1e-4 * (positions - origins[box]) + origins[box] + far).astype(np.float32)
    assert not mesh_data.closed_outward(tiny, triangles, origins + far, box)


def test_occluder_triangles_come_wound_outward_whatever_the_mesh_winding():
    # The pre-pass draws its occluders' front faces only (preview/draw.py, mesh_data.wound_outward):
    # a back face seen nearly edge-on may tilt its depth plane nearer than the front face.
    from boxmarch import scenes

    rng = np.random.default_rng(3)
    positions, _edges, _starts, _sizes, corner_verts = scenes.box_arrays(
        rng.uniform(-5, 5, (6, 3)) + [800.0, 0.0, 0.0], rng.uniform(0.2, 1.0, (6, 3)), scenes.random_rotations(6, rng))
    quads = corner_verts.reshape(-1, 4)
    outward = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    box = np.repeat(np.arange(6), 8)
    origins = np.array([positions[box == b].mean(axis=0) for b in range(6)])
    assert mesh_data.closed_outward(positions, outward, origins, box)
    mixed = outward.copy()
    turned = np.isin(box[outward[:, 0]], [1, 4]) | (rng.random(len(outward)) < 0.2)  # two boxes, and strays
    mixed[turned] = outward[turned][:, ::-1]
    wound = mesh_data.wound_outward(positions.astype(np.float32), mixed, origins.astype(np.float32), box)
    assert mesh_data.closed_outward(positions, wound, origins, box)
    assert np.array_equal(np.sort(wound, axis=1), np.sort(outward, axis=1))  # the same triangles
    assert not mesh_data.closed_outward(positions, mixed, origins, box)  # which were not outward
    assert np.array_equal(mesh_data.wound_outward(positions, outward, origins, box), outward)
    # the mesh's int32 triangles stay int32: a GPU index buffer of int64 drew nothing at all
    assert mesh_data.wound_outward(positions, mixed.astype(np.int32), origins, box).dtype == np.int32


def test_a_box_the_near_plane_cuts_draws_no_occluders():
    """The pre-pass rule of every implementation (preview.vert.glsl, three.js, occluder_depths): a
    box that the near plane cuts draws no occluders, though it does not hold the eye. Sphere N
    (radius 0.3 at z = -0.25, beside the eye) reaches past the near plane at z = -0.1; box F (a
    sphere of radius 1 at z = -4) lies behind it. Were N's occluders drawn, F's fragments behind
    them would count as occluded; with the rule none are, and the picture is the one without."""
    near = 0.1
    projection = perspective({"fov": 90.0, "near": near, "far": 100.0}, 1.0)
    origins, half = [[0.35, 0.0, -0.25], [0.0, 0.0, -4.0]], [[0.3, 0.3, 0.3], [1.0, 1.0, 1.0]]
    q = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))
    eye_outside = np.any(np.abs(np.zeros(3) - origins[0]) > half[0])
    cuts_near_plane = origins[0][2] + half[0][2] > -near
    assert eye_outside and cuts_near_plane

    def draw(**plan):
        return core.render_boxes(origins, q, half, projection, np.eye(4), 32, 32, sdf="SPHERE", **plan)

    with_occluders = draw(occluders=True)
    assert with_occluders.cost["occluded_fragments"] == 0
    assert np.array_equal(with_occluders.depth, draw().depth)

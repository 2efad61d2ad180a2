"""The shipped Unity material (shaders/hlsl/boxmarch_example.hlsl) run on what Unity holds: the
UNITY preset's default layout (UV_FRAME) for a static mesh, and NORMAL_FRAME for a skinned rig
posed 40 degrees at each joint. Unity cannot run here: the UNITY export's FBX
is read back (tests/fbx_reader.py) and put through the importer's documented conversions
(engine_scene.UNITY: x negated, UVs as written, float32 with Read/Write on); the HLSL is
compiled to SPIR-V by glslangValidator's HLSL front end, translated to GLSL ES by SPIRV-Cross and
drawn by WebGL 2 in headless Chromium (tests/engines/hlsl_webgl.py), with the material's map()
replaced by a box at 0.6 of each box's own half-extents. The pixels must cover each box's
projected silhouette, from the generating geometry in Unity's frame (posed by the test's own
forward kinematics for the rig), within 1 px. Negative controls: the static mesh with its
quaternion channels dropped (identity frame), the rig with its normal and tangent left at rest
(what a frame in UV maps gives a skinned mesh); both must fail."""
import numpy as np
import pytest

from boxmarch.formats import shader_sources
from tests.engine_scene import (UNITY, baked_scene, imported, posed_rig_boxes, rig_boxes, silhouettes, skinned_scene,
                                unity_skinned_vertices)
from tests.engines import Shot, coverage_mismatch, hlsl_webgl, ndc_to_pixels
from tests.fbx_reader import read_fbx_geometry, read_fbx_skin
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders and Blender exports

W, H = 320, 240
# Cameras in Unity's frame: the static boxes, and the posed rig seen from its side.
STATIC_CAMERA = (np.array([-9.0, 8.0, -12.0]), np.array([-0.5, -0.5, 0.0]))
RIG_CAMERA = (np.diag([-1.0, 1.0, 1.0]) @ [8.9, 4.35, -2.2], np.diag([-1.0, 1.0, 1.0]) @ [0.9, 1.85, 1.8])
SHIPPED_MAP = ("return op_smooth_union(sdf_preset_sphere(p, box_half), sdf_preset_torus(p, box_half), "
               "0.05 * max3(box_half));")
INNER = 0.6


def look_at(eye, target, fov_deg=50.0, near=0.5, far=100.0):
    """(view, projection), 4 x 4 each (GL clip space), of a camera at ``eye`` looking at
    ``target``, y up, for a W x H image."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    view = np.eye(4)
    view[:3, :3] = np.stack([right, up, -forward])
    view[:3, 3] = -view[:3, :3] @ eye
    f = 1.0 / np.tan(np.radians(fov_deg) / 2)
    projection = np.array([[f * H / W, 0, 0, 0], [0, f, 0, 0],
                           [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]])
    return view, projection


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """layout -> the example material's two stages in GLSL ES, its map() a box at INNER."""
    need(hlsl_webgl.available())
    hlsl = shader_sources.shader_dir() / "hlsl"
    text = (hlsl / "boxmarch_example.hlsl").read_text()
    assert SHIPPED_MAP in text
    path = tmp_path_factory.mktemp("hlsl") / "example.hlsl"
    path.write_text(text.replace(SHIPPED_MAP, f"return sd_box(p, {INNER} * box_half);"))
    return {layout: {stage: hlsl_webgl.to_glsl_es(path, stage, stage, [f"_LAYOUT_{layout}"], [hlsl])
                     for stage in ("vert", "frag")} for layout in ("UV_FRAME", "NORMAL_FRAME")}


@pytest.fixture(scope="module")
def closed_form_example(tmp_path_factory):
    """The example material with its map() a box at INNER solved in closed form (BM_CLOSED_FORM,
    boxmarch_raymarch.hlsl) instead of marched, and as the negative control the closed form of
    the whole box; UV_FRAME layout."""
    need(hlsl_webgl.available())
    hlsl = shader_sources.shader_dir() / "hlsl"
    text = (hlsl / "boxmarch_example.hlsl").read_text().replace(SHIPPED_MAP, f"return sd_box(p, {INNER} * box_half);")
    programs = {}
    for name, half in (("inner", f"{INNER} * box_half"), ("whole", "box_half")):
        path = tmp_path_factory.mktemp("hlsl_closed") / "example.hlsl"
        path.write_text(f"#define BM_CLOSED_FORM bm_hit_box(ro, rd, {half})\n" + text)
        programs[name] = {stage: hlsl_webgl.to_glsl_es(path, stage, stage, ["_LAYOUT_UV_FRAME"], [hlsl])
                          for stage in ("vert", "frag")}
    return programs


@pytest.fixture
def unity_mesh(blender, tmp_path):
    _ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path / "boxes.fbx"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="UNITY") == {"FINISHED"}
    raw = read_fbx_geometry(path)
    positions, uvs = imported(raw, UNITY)
    corners = raw["triangles"].reshape(-1)
    attributes = {"v_vertex": np.c_[positions, np.ones(len(positions))][corners]}
    attributes.update({f"v_uv{k}": uv[corners] for k, uv in enumerate(uvs, start=1)})
    return attributes, len(corners), centres, sizes, rotations


def draw(programs, attributes, count, camera):
    eye, target = camera
    view, projection = look_at(eye, target)
    vp = projection @ view
    # Matrices column by column: HLSL's default (column_major) constant buffer packing.
    uniforms = {"unity_ObjectToWorld": np.eye(4).ravel().tolist(), "unity_WorldToObject": np.eye(4).ravel().tolist(),
                "unity_MatrixVP": vp.T.ravel().tolist(), "_WorldSpaceCameraPos": list(eye),
                "_WorldSpaceLightPos0": [0.0, 1.0, 0.0, 0.0], "_Color": [1.0, 1.0, 1.0, 1.0],
                "_UVChannels": [1.0, 2.0, 0.0, 0.0], "_HalfExtents": [0.0, 0.0, 0.0, 0.0], "_MaxSteps": 256,
                "_Epsilon": 1e-4, "_Relaxation": 1.0, "_MaxDistance": 1000.0, "_Quality": 1.0,
                "_ScreenParams": [float(W), float(H), 1.0 + 1.0 / W, 1.0 + 1.0 / H]}
    pixels = hlsl_webgl.render(programs["vert"], programs["frag"], attributes, uniforms, count, W, H)
    return Shot(pixels, view, ndc_to_pixels(W, H) @ vp)


def unity_silhouettes(shot, centres, sizes, rotations):
    """The silhouettes of the raymarched boxes (INNER of each box, Blender's frame in) in Unity's frame."""
    return silhouettes(shot, centres, INNER * sizes, rotations, UNITY["to_engine"])


def test_unity_material_raymarches_each_box_where_unity_holds_it(example, unity_mesh):
    attributes, count, centres, sizes, rotations = unity_mesh
    shot = draw(example["UV_FRAME"], attributes, count, STATIC_CAMERA)
    covered = shot.pixels[..., 3] > 0
    expected = unity_silhouettes(shot, centres, sizes, rotations)
    for polygon in expected:  # every box in the picture
        assert polygon.min() > 0 and polygon[:, 0].max() < W and polygon[:, 1].max() < H
    mismatch = coverage_mismatch(covered, expected)
    assert mismatch is None, mismatch
    assert covered.sum() > 500


def test_unity_material_hits_in_closed_form(closed_form_example, unity_mesh):
    """BM_CLOSED_FORM in place of the march (the presets' hits, shaders/glsl/raymarch.glsl, in
    boxmarch_march.hlsl): the boxes at INNER land on their silhouettes; the whole boxes' closed
    form (the negative control) does not."""
    attributes, count, centres, sizes, rotations = unity_mesh
    shot = draw(closed_form_example["inner"], attributes, count, STATIC_CAMERA)
    expected = unity_silhouettes(shot, centres, sizes, rotations)
    inner = shot.pixels[..., 3] > 0
    whole = draw(closed_form_example["whole"], attributes, count, STATIC_CAMERA).pixels[..., 3] > 0
    assert inner.sum() > 500
    assert coverage_mismatch(inner, expected) is None, coverage_mismatch(inner, expected)
    assert coverage_mismatch(whole, expected) is not None


def test_unity_material_without_the_frame_fails(example, unity_mesh):
    attributes, count, centres, sizes, rotations = unity_mesh
    dropped = dict(attributes)
    dropped["v_uv1"] = np.zeros_like(attributes["v_uv1"])                           # q.xy = 0
    dropped["v_uv2"] = np.tile([0.0, 1.0], (len(attributes["v_uv2"]), 1))           # q.zw = (0, 1)
    shot = draw(example["UV_FRAME"], dropped, count, STATIC_CAMERA)
    covered = shot.pixels[..., 3] > 0
    assert covered.sum() > 500  # it drew, in the wrong places
    assert coverage_mismatch(covered, unity_silhouettes(shot, centres, sizes, rotations)) is not None


def test_unity_material_follows_the_skinned_rig(blender, tmp_path, example):
    """The rig exported with the UNITY preset (NORMAL_FRAME, a Skin deformer), posed by Unity's
    skinning as modelled (engine_scene.unity_skinned_vertices), drawn by the material reading the
    skinned normal and tangent."""
    from boxmarch.export import scene

    ob, _rig = skinned_scene(blender)
    path = tmp_path / "skinned.fbx"
    assert scene.export_objects(blender.context, [ob], "UNITY", str(path))["layout"] == "NORMAL_FRAME"
    raw = read_fbx_geometry(path)
    positions, normals, tangents, rest_normals, rest_tangents = unity_skinned_vertices(raw, read_fbx_skin(path))
    corners = raw["triangles"].reshape(-1)
    attributes = {"v_vertex": np.c_[positions, np.ones(len(positions))][corners],
                  **{f"v_uv{k}": raw[name][corners] for k, name in
                     enumerate(("BoxOffsetXY", "BoxOffsetZIndex", "BoxHalfXY", "BoxHalfZ"), start=1)}}
    _centres, sizes, _rotations, _bones = rig_boxes()
    posed_centres, posed_rotations = posed_rig_boxes()
    for frame, (n, t) in (("skinned", (normals, tangents)), ("rest", (rest_normals, rest_tangents))):
        shot = draw(example["NORMAL_FRAME"], {**attributes, "v_normal": n[corners], "v_tangent": t[corners]}, len(corners),
                    RIG_CAMERA)
        covered = shot.pixels[..., 3] > 0
        assert covered.sum() > 500, frame
        expected = unity_silhouettes(shot, posed_centres, sizes, posed_rotations)
        mismatch = coverage_mismatch(covered, expected)
        if frame == "skinned":
            for polygon in expected:
                assert polygon.min() > 0 and polygon[:, 0].max() < W and polygon[:, 1].max() < H
            assert mismatch is None, mismatch
        else:
            assert mismatch is not None

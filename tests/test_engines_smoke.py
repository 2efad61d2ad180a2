"""Smoke tests of the engine harnesses (tests/engines) on a .glb written by hand here, so every
value the engines report is known independently of boxmarch's exporter."""
import json
import struct

import numpy as np
import pytest

from tests.engines import coverage_mismatch, godot3, threejs
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium and Godot 3 runs

W, H = 160, 120
CAMERA = {"position": [0.0, 0.0, 5.0], "target": [0.0, 0.0, 0.0], "up": [0, 1, 0], "fov": 40.0}
ORTHO = {"position": [0.0, 0.0, 5.0], "target": [0.0, 0.0, 0.0], "ortho": 1.5}
F32 = np.float32

# Two quads: "Left" holds its world positions; "Right" is a tilted quad placed by its node's
# translation, so the engines' node transforms are part of what is checked.
QUADS = [
    {"name": "Left", "translation": [0.0, 0.0, 0.0],
     "positions": [[-2.0, -0.5, 0.0], [-0.6, -0.5, 0.0], [-0.6, 0.7, 0.0], [-2.0, 0.7, 0.0]]},
    {"name": "Right", "translation": [1.2, -0.1, 0.0],
     "positions": [[-0.5, -0.6, 0.3], [0.5, -0.6, -0.3], [0.5, 0.6, -0.3], [-0.5, 0.6, 0.3]]},
]
# Values whose float32 bits are not short decimals, outside [0, 1] for the UVs.
UV2 = np.array([[0.1, 1 / 3], [-0.7, 2.5], [12345.678, -1e-3], [0.2, 0.9]], dtype=F32)
COLOR = np.array([[0.1, 0.2, 0.3, 0.4], [0.5, 0.6, 0.7, 0.8],
                  [0.9, 0.123, 0.456, 0.789], [1 / 3, 2 / 3, 0.01, 1.0]], dtype=F32)
UV0 = np.array([[0.1, 0.7], [0.3, 0.3], [0.6, 0.9], [0.55, 0.123]], dtype=F32)
NORMAL = np.array([[0.28, 0.0, 0.96], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0], [-0.48, 0.6, 0.64]], dtype=F32)
INDEX = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint16)


def make_glb(quads):
    """A binary glTF 2.0 file: one node and one mesh per quad, float32 POSITION, NORMAL,
    TEXCOORD_0, TEXCOORD_1 and COLOR_0 (VEC4), uint16 indices."""
    blob, views, accessors, meshes, nodes = bytearray(), [], [], [], []

    def add(array, kind, component, target, minmax=False):
        data = np.ascontiguousarray(array).tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": target})
        blob.extend(data + b"\0" * (-len(data) % 4))
        acc = {"bufferView": len(views) - 1, "componentType": component, "count": len(array),
               "type": kind}
        if minmax:
            acc["min"], acc["max"] = array.min(0).tolist(), array.max(0).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    for i, q in enumerate(quads):
        pos = np.array(q["positions"], dtype=F32)
        attributes = {"POSITION": add(pos, "VEC3", 5126, 34962, True),
                      "NORMAL": add(NORMAL, "VEC3", 5126, 34962),
                      "TEXCOORD_0": add(UV0, "VEC2", 5126, 34962),
                      "TEXCOORD_1": add(UV2 + F32(i), "VEC2", 5126, 34962),
                      "COLOR_0": add(COLOR, "VEC4", 5126, 34962)}
        meshes.append({"name": q["name"], "primitives": [
            {"attributes": attributes, "indices": add(INDEX, "SCALAR", 5123, 34963), "mode": 4}]})
        nodes.append({"name": q["name"], "mesh": i, "translation": q["translation"]})
    doc = {"asset": {"version": "2.0"}, "scene": 0,
           "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
           "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    body += struct.pack("<II", len(blob), 0x004E4942) + bytes(blob)
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def moved(dx):
    """QUADS with the Right quad's node moved by dx along x."""
    quads = [dict(q) for q in QUADS]
    quads[1]["translation"] = [quads[1]["translation"][0] + dx] + quads[1]["translation"][1:]
    return quads


def world_corners(quad):
    return np.array(quad["positions"]) + np.array(quad["translation"])


def check_shot(shot):
    """coverage_mismatch of the shot's non-background pixels against QUADS projected with the
    shot's own camera matrices."""
    covered = shot.pixels[..., :3].max(axis=2) > 127
    return coverage_mismatch(covered, [shot.project(world_corners(q)) for q in QUADS])


# --- three.js ----------------------------------------------------------------------------------

WHITE_JS = """
function createWhiteMaterial(THREE) {
  return new THREE.ShaderMaterial({
    vertexShader: 'void main() { gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
    fragmentShader: 'void main() { gl_FragColor = vec4(1.0); }',
    side: THREE.DoubleSide});
}"""
WHITE_SETUP = "gltf.scene.traverse(function (o) { if (o.isMesh) o.material = createWhiteMaterial(THREE); });"


def test_threejs_receives_the_written_floats():
    need(threejs.available())
    meshes = threejs.load_attributes(make_glb(QUADS))
    assert [m["name"] for m in meshes] == ["Left", "Right"]
    for i, (m, q) in enumerate(zip(meshes, QUADS)):
        a = m["attributes"]
        assert set(a) == {"position", "normal", "uv", "uv2", "color"}
        assert not any(m["normalized"].values())
        for name, want in (("position", np.array(q["positions"], F32)), ("normal", NORMAL),
                           ("uv", UV0), ("uv2", UV2 + F32(i)), ("color", COLOR)):
            assert a[name].shape == want.shape, name
            # float32 -> float64 is exact: equality here is bit equality of the float32 values
            assert np.array_equal(a[name], want.astype(np.float64)), name
        assert np.array_equal(m["index"], INDEX)
        want_world = np.eye(4)
        want_world[:3, 3] = q["translation"]
        assert np.allclose(m["matrixWorld"], want_world, atol=1e-7)


@pytest.mark.parametrize("camera", [CAMERA, ORTHO], ids=["perspective", "ortho"])
def test_threejs_draws_where_its_camera_projects(camera):
    need(threejs.available())
    shot = threejs.render(make_glb(QUADS), WHITE_JS, WHITE_SETUP, W, H, camera)
    assert shot.pixels.shape == (H, W, 4)
    assert set(np.unique(shot.pixels[..., 0])) == {0, 255}
    assert check_shot(shot) is None, check_shot(shot)
    # negative control: the Right quad's node moved 0.1 units (about 2.5 px) in the file
    moved_shot = threejs.render(make_glb(moved(0.1)), WHITE_JS, WHITE_SETUP, W, H, camera)
    assert check_shot(moved_shot) is not None


def test_threejs_reports_page_errors():
    need(threejs.available())
    with pytest.raises(RuntimeError, match="boom"):
        threejs.render(make_glb(QUADS), "", "throw new Error('boom');", 8, 8, CAMERA)


# --- Godot 3 -----------------------------------------------------------------------------------

WHITE_GDSHADER = """shader_type spatial;
render_mode unshaded, cull_disabled;
uniform float level = 0.0;
uniform vec3 mask = vec3(0.0);
void fragment() { ALBEDO = level * mask; }
"""
WHITE_UNIFORMS = {"level": 1.0, "mask": [1.0, 1.0, 1.0]}  # black unless uniforms arrive


@pytest.fixture(scope="module")
def godot_projects(tmp_path_factory):
    """The QUADS file imported twice: {compress: project_dir}."""
    need(godot3.available())
    projects = {}
    for compress in (False, True):
        projects[compress] = tmp_path_factory.mktemp(f"godot-compress-{compress}")
        godot3.import_gltf(make_glb(QUADS), projects[compress], compress=compress)
    return projects


def godot_surfaces(project):
    surfaces = godot3.dump_arrays(project)
    assert [(s["name"], s["surface"]) for s in surfaces] == [("Left", 0), ("Right", 0)]
    for s, q in zip(surfaces, QUADS):
        assert np.array_equal(s["vertex"], np.array(q["positions"], F32).astype(np.float64))
        assert np.allclose(s["transform"][:3, 3], q["translation"], atol=1e-7)
        # Godot turns glTF's counter-clockwise triangles clockwise (its front faces)
        assert np.array_equal(s["index"], INDEX.reshape(-1, 3)[:, [0, 2, 1]].ravel())
        assert s["bones"] is None and s["weights"] is None
    return surfaces


def test_godot_uncompressed_import_keeps_the_written_floats(godot_projects):
    for i, s in enumerate(godot_surfaces(godot_projects[False])):
        for name, want in (("normal", NORMAL), ("uv", UV0), ("uv2", UV2 + F32(i)), ("color", COLOR)):
            assert np.array_equal(s[name], want.astype(np.float64)), name
        assert s["tangent"] is not None  # the importer's ensure_tangents generates them


def test_godot_compressed_import_is_8_bit_colour_and_half_float_uv2(godot_projects):
    """What the default (compressed) import delivers, measured: positions stay float32 (checked
    in godot_surfaces); colour is 8-bit unorm, normals 8-bit snorm, uv and uv2 half floats, each
    truncated rather than rounded."""
    def half(v):  # float32 -> half by truncation toward zero (the mantissa cut to 10 bits)
        return (v.view(np.uint32) & np.uint32(0xFFFFE000)).view(F32)

    for i, s in enumerate(godot_surfaces(godot_projects[True])):
        # 8-bit unorm by truncation, not rounding: 0.1 -> 25/255, 0.3 -> 76/255, 0.01 -> 2/255
        truncated = np.floor(COLOR * F32(255)) / F32(255)
        assert np.array_equal(s["color"], truncated), "colour is 8-bit, truncated"
        assert not np.array_equal(truncated, np.round(COLOR * F32(255)) / F32(255))
        # -0.7 -> -0.69970703 where rounding would give -0.70019531
        assert np.array_equal(s["uv2"], half(UV2 + F32(i))), "uv2 is half float, truncated"
        assert not np.array_equal(half(UV2 + F32(i)), (UV2 + F32(i)).astype(np.float16).astype(F32))
        assert np.array_equal(s["uv"], half(UV0)), "uv is half float, truncated"
        # 0.96 -> 121/127, -0.48 -> -60/127
        assert np.array_equal(s["normal"], np.trunc(NORMAL * F32(127)) / F32(127)), "normal is snorm8"


@pytest.mark.parametrize("camera", [CAMERA, ORTHO], ids=["perspective", "ortho"])
def test_godot_draws_where_its_camera_projects(godot_projects, tmp_path, camera):
    shot = godot3.render(godot_projects[False], WHITE_GDSHADER, width=W, height=H, camera=camera,
                         uniforms=WHITE_UNIFORMS)
    assert shot.pixels.shape == (H, W, 4)
    assert check_shot(shot) is None, check_shot(shot)
    if not threejs.available():  # the two engines' cameras agree for the same camera dict
        corners = world_corners(QUADS[1])
        three_shot = threejs.render(make_glb(QUADS), "", "", W, H, camera)
        assert np.allclose(shot.project(corners), three_shot.project(corners), atol=1e-3)
    # negative control: the Right quad's node moved 0.1 units in the file
    moved_project = tmp_path / "moved"
    godot3.import_gltf(make_glb(moved(0.1)), moved_project, compress=False)
    moved_shot = godot3.render(moved_project, WHITE_GDSHADER, width=W, height=H, camera=camera,
                          uniforms=WHITE_UNIFORMS)
    assert check_shot(moved_shot) is not None


def test_godot_reports_shader_errors(godot_projects):
    with pytest.raises(RuntimeError, match="SHADER ERROR"):
        godot3.render(godot_projects[False], "shader_type spatial;\nvoid fragment() { ALBEDO = nope; }\n",
                      width=8, height=8, camera=CAMERA)

"""A chain baked and exported with every default (no axis sorting, the presets' own layouts) draws
as chain links in three.js r111 and r180 (headless Chromium), Godot 3 (under xvfb) and the
Blender preview: the LINK preset reads the box's axes by extent (shaders/glsl/sdf.glsl,
bm_by_extent). Each picture is compared within 1 px with the links raymarched in float64 from the
generating geometry alone (tests/engine_chain.py). The negative control, in every engine: the
preset as it read the box's axes by name (local x the length, z the thickness), which fits only a
bake with Sort Axes by Extent, must fail the same check on the same file (it drew slivers)."""
import json

import numpy as np
import pytest

from tests.conftest import empty_scene, mesh_object
from tests.engine_chain import chain_links, link_coverage
from tests.engine_scene import TO_Y_UP
from tests.engines import Shot, godot3, mask_mismatch, ndc_to_pixels, threejs
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Blender bake and export, Chromium, Godot 3 and preview renders

W, H = 400, 300
# Y-up engine frame (Blender (x, y, z) -> (x, z, -y)): from the front (Blender -y), a little above and right.
CAMERA = {"position": [1.5, 4.5, 7.0], "target": [0.0, 2.6, 0.0], "fov": 40, "near": 0.5, "far": 50}


def axes_by_name(half, point):
    """The LINK preset's body as it was before it read axes by extent (the control), in a map()
    of the engine's language: ``half`` names the box's half-extents, ``point`` the point."""
    return (f"float t = min({half}.z, 0.25 * min({half}.x, {half}.y));\n"
            f"return sd_link({point}.yxz, max({half}.x - {half}.y, 0.0), {half}.y - t, t);")


THREEJS_LINK, THREEJS_CONTROL = "return sdf_preset_link(p, box_half);", axes_by_name("box_half", "p")
GODOT_LINK, GODOT_CONTROL = "return sdf_preset_link(p, h);", axes_by_name("h", "p")
PREVIEW_CONTROL = "float map(vec3 p)\n{\n" + axes_by_name("box_half", "p") + "\n}\n"


def preview_shots(bpy, ob):
    """The preview's LINK preset and the control as a user SDF, rendered from CAMERA (moved into
    Blender's frame) as Shots."""
    import mathutils

    from boxmarch import preview

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    bpy.context.scene.collection.objects.link(camera)
    eye, target = TO_Y_UP.T @ CAMERA["position"], TO_Y_UP.T @ CAMERA["target"]
    camera.location = eye
    camera.rotation_euler = mathutils.Vector(target - eye).to_track_quat("-Z", "Y").to_euler()
    camera.data.sensor_fit = "VERTICAL"
    camera.data.angle = np.radians(CAMERA["fov"])
    text = bpy.data.texts.new("axes_by_name.glsl")
    text.write(PREVIEW_CONTROL)
    ob.boxmarch.preview = True
    shots = {}
    for name, sdf in (("link", "LINK"), ("control", "USER")):
        ob.boxmarch.sdf = sdf
        ob.boxmarch.user_text = text.name
        rgba, _depth = preview.render(bpy.context.scene, camera, W, H)
        view, projection = preview.camera_matrices(bpy.context.scene, camera, W, H)
        shots[name] = Shot((np.clip(rgba, 0, 1) * 255).astype(np.uint8), view, ndc_to_pixels(W, H) @ projection @ view)
    return shots


@pytest.fixture(scope="module")
def chain(bpy_module, tmp_path_factory):
    """The chain baked with bpy.ops.boxmarch.bake() and exported with the GLTF and GODOT3 presets,
    no option given; the preview's shots; the bake's half-extents."""
    from boxmarch import core, mesh_io, scenes

    bpy = empty_scene(bpy_module)
    centres, sizes, rotations = chain_links()
    ob = mesh_object(bpy, "chain", *scenes.box_arrays(centres, sizes, rotations))
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    layers = mesh_io.read_baked_layers(ob.data)
    _origins, _quaternions, baked_half = core.boxes_from_bake(
        mesh_io.read_positions(ob.data), layers.shader_offsets(), layers.vertex_quaternions(),
        np.repeat(np.arange(len(centres)), 8))
    folder = tmp_path_factory.mktemp("default_links")
    files = {}
    for preset in ("GLTF", "GODOT3"):
        path = folder / f"{preset}.glb"
        assert bpy.ops.boxmarch.export(filepath=str(path), preset=preset) == {"FINISHED"}
        files[preset] = path.read_bytes()
    files["table"] = (folder / "GODOT3.boxes.tres").read_bytes()
    return files, preview_shots(bpy, ob), baked_half, (centres, sizes, rotations)


def covered(shot, background_alpha=True):
    return shot.pixels[..., 3] > 0 if background_alpha else shot.pixels[..., :3].max(axis=2) > 20


def assert_links_and_control_fails(link, control, boxes, to_engine, background_alpha=True):
    expected = link_coverage(link, *boxes, to_engine)
    assert expected.sum() > 3000  # links of tens of pixels, not dots
    mismatch = mask_mismatch(covered(link, background_alpha), expected)
    assert mismatch is None, mismatch
    assert covered(control, background_alpha).sum() > 100  # the control drew, in the wrong shape
    assert mask_mismatch(covered(control, background_alpha), link_coverage(control, *boxes, to_engine)) is not None


def test_the_default_bake_leaves_the_link_axes_unsorted(chain):
    """The precondition of every check here: with the defaults, no box's local x is its length."""
    _files, _shots, baked_half, _boxes = chain
    assert np.all(baked_half.argmax(axis=1) != 0), baked_half


@pytest.mark.parametrize("release", sorted(threejs.RELEASES))
def test_threejs_draws_links_from_a_default_export(chain, release):
    need(threejs.available(release))
    files, _shots, _half, boxes = chain

    def setup(body):
        return ("gltf.scene.traverse(function (o) { if (!o.isMesh) return; useBoxmarchMaterial(THREE, o, "
                f"createBoxmarchMaterial(THREE, {{map: {json.dumps(body)}, maxSteps: 256}})); }});")

    jobs = [threejs.render_job(setup(body), W, H, CAMERA) for body in (THREEJS_LINK, THREEJS_CONTROL)]
    link, control = threejs.run_jobs(files["GLTF"], jobs, threejs.shipped_material(release), release)
    assert_links_and_control_fails(link, control, boxes, TO_Y_UP)


def test_godot3_draws_links_from_a_default_export(chain, tmp_path):
    need(godot3.available())
    files, _shots, _half, boxes = chain
    project = str(tmp_path / "project")
    godot3.import_gltf(files["GODOT3"], project, compress=False, extra_files={"model.boxes.tres": files["table"]})
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    link, control = (godot3.render(project, godot3.shipped_shader(body), width=W, height=H, camera=CAMERA,
                                   uniforms=uniforms) for body in (GODOT_LINK, GODOT_CONTROL))
    assert_links_and_control_fails(link, control, boxes, TO_Y_UP, background_alpha=False)


def test_preview_draws_links_from_a_default_bake(chain):
    _files, shots, _half, boxes = chain
    assert_links_and_control_fails(shots["link"], shots["control"], boxes, np.eye(3))

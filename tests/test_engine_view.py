"""The export presets' local frame in the raymarch preview (docs/EXPORT.md): with Engine View
UNITY the preview evaluates the SDF with local x mirrored, as Unity's left-handed object frames
do, so an artist sees in Blender what the engine will show."""
import numpy as np
import pytest

from boxmarch import scenes
from boxmarch.formats import shader_sources
from tests.conftest import mesh_object
from tests.helpers.glsl import compile_glsl

# A sphere off-centre along local +x: not symmetric in local x, so a mirror moves it.
OFF_CENTRE = "float map(vec3 p)\n{\n  return length(p - vec3(0.45, 0.0, 0.0)) - 0.3;\n}\n"


def test_mirrored_sources_compile(tmp_path):
    for name, source in (("preset", shader_sources.fragment_source("LINK", None, (-1.0, 1.0, 1.0))),
                         ("user", shader_sources.fragment_source("USER", OFF_CENTRE, (-1.0, 1.0, 1.0)))):
        proc = compile_glsl(tmp_path, f"engine_{name}", "frag", source)
        assert proc.returncode == 0, proc.stdout + proc.stderr
    assert shader_sources.fragment_source("BOX", None, (1.0, 1.0, 1.0)) == shader_sources.fragment_source("BOX")


@pytest.mark.slow
def test_unity_engine_view_mirrors_an_asymmetric_sdf(blender):
    bpy = blender
    from boxmarch import preview

    # One box, longest side along world x: sorted axes put local x along world +-x.
    arrays = scenes.box_arrays(np.zeros((1, 3)), np.array([[2.0, 1.5, 1.0]]), np.eye(3)[None])
    ob = mesh_object(bpy, "Box", *arrays)
    assert bpy.ops.boxmarch.bake(sort_axes_by_extent=True) == {"FINISHED"}
    text = bpy.data.texts.new("off_centre")
    text.write(OFF_CENTRE)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    bpy.context.scene.collection.objects.link(camera)
    camera.location = (0.0, -8.0, 0.0)
    camera.rotation_euler = (np.pi / 2, 0.0, 0.0)  # looks along +y: image x is world x
    ob.boxmarch.sdf = "USER"
    ob.boxmarch.user_text = text.name
    ob.boxmarch.preview = True
    centroids = {}
    for engine in ("BLENDER", "UNITY", "GLTF"):
        ob.boxmarch.engine = engine
        rgba, _ = preview.render(bpy.context.scene, camera, 96, 64)
        covered = rgba[..., 3] > 0
        assert covered.sum() > 20, engine
        centroids[engine] = np.argwhere(covered)[:, 1].mean() - (96 - 1) / 2  # pixels right of centre
    assert abs(centroids["BLENDER"]) > 5  # 0.45 units off centre: about 7.5 pixels here
    assert abs(centroids["UNITY"] + centroids["BLENDER"]) < 1.0  # mirrored about it
    assert abs(centroids["GLTF"] - centroids["BLENDER"]) < 1e-9  # glTF turns, never mirrors

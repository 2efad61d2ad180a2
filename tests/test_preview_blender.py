"""The preview's Blender side in the bpy module: per-object settings, the baked data it reads and
the decoded-vector overlay (the GPU image itself is checked in tests/test_preview.py)."""
import numpy as np
import pytest

from tests.conftest import mesh_object
from boxmarch import core, scenes
from boxmarch.formats import layouts


def baked_boxes(blender, encoding="FLOAT_COLOR", domain="POINT"):
    arrays, centres, sizes, _rotations = scenes.random_boxes(12, seed=4, spread=5.0, size_range=(0.3, 2.0))
    ob = mesh_object(blender, "boxes", *arrays)
    assert blender.ops.boxmarch.bake(encoding=encoding, domain=domain) == {"FINISHED"}
    return ob, centres, sizes


def test_settings_contract(blender):
    ob, _, _ = baked_boxes(blender)
    settings = ob.boxmarch
    assert settings.preview is False and settings.sdf == "BOX"
    items = {item.identifier for item in settings.bl_rna.properties["sdf"].enum_items}
    assert {"BOX", "SPHERE", "USER"} <= items
    for name in ("max_steps", "epsilon", "relaxation", "max_distance", "quality", "show_outline", "user_text"):
        assert name in settings.bl_rna.properties
    quality = settings.bl_rna.properties["quality"]
    assert settings.quality == 1.0 and quality.hard_max == 1.0 and quality.hard_min > 0.0  # 1: the full march
    ob.display_type = "SOLID"
    settings.preview = True
    assert ob.display_type == "WIRE"  # the solid box would hide the raymarched shape inside it
    settings.preview = False
    assert ob.display_type == "SOLID"


@pytest.mark.parametrize("encoding, domain, tolerance", [("FLOAT_COLOR", "POINT", 1e-5), ("FLOAT_COLOR", "CORNER", 1e-5),
                                                         ("BYTE_COLOR", "POINT", 0.02)])
def test_read_baked_recovers_boxes_and_vectors_meet_at_origins(blender, encoding, domain, tolerance):
    from boxmarch.preview import mesh_data

    ob, centres, sizes = baked_boxes(blender, encoding, domain)
    baked = mesh_data.read_baked(ob.data)
    scale = sizes.max()
    # every box's half-extents, as a set per box (the baked frame may order the axes differently)
    assert np.allclose(np.sort(baked.box_half_extents, axis=1), np.sort(sizes / 2, axis=1), atol=tolerance * scale)
    assert np.allclose(baked.origins, centres, atol=tolerance * scale)
    raw, rotated = mesh_data.vector_lines(baked.positions, core.decode_offsets(baked.offsets),
                                          layouts.quaternion_matrices(baked.quaternions))
    assert raw.shape == rotated.shape == (2 * len(baked.positions), 3)
    assert np.array_equal(rotated[0::2], baked.positions)
    tips = rotated[1::2].reshape(-1, 8, 3)  # 8 vertices per box, in order
    assert np.abs(tips - centres[:, None, :]).max() <= tolerance * scale
    assert np.abs(raw[1::2].reshape(-1, 8, 3) - centres[:, None, :]).max() > 0.1  # raw f is box-local


def test_unbaked_mesh_is_refused(blender):
    from boxmarch.preview import mesh_data

    arrays, *_ = scenes.random_boxes(2, seed=1)
    ob = mesh_object(blender, "plain", *arrays)
    with pytest.raises(mesh_data.NotBakedError, match="not baked"):
        mesh_data.read_baked(ob.data)


def test_toggle_operator_switches_selected_meshes(blender):
    ob, _, _ = baked_boxes(blender)
    arrays, *_ = scenes.random_boxes(2, seed=9)
    plain = mesh_object(blender, "plain", *arrays)
    ob.select_set(True)
    plain.select_set(True)
    assert blender.ops.boxmarch.preview_toggle() == {"FINISHED"}
    assert ob.boxmarch.preview and plain.boxmarch.preview
    assert blender.ops.boxmarch.preview_toggle() == {"FINISHED"}
    assert not ob.boxmarch.preview and not plain.boxmarch.preview


def test_cache_handlers_survive_loading_a_file(blender):
    from boxmarch import preview

    blender.ops.wm.read_factory_settings(use_empty=True)  # loading a file drops non-persistent handlers
    for list_name, function in preview.APP_HANDLERS:
        assert function in getattr(blender.app.handlers, list_name), list_name


def test_new_sdf_text_template_compiles(blender, tmp_path):
    import shutil
    import subprocess

    from boxmarch.formats import shader_sources
    from tests.helpers.glsl import blender_declarations

    ob, _, _ = baked_boxes(blender)
    assert blender.ops.boxmarch.new_sdf_text() == {"FINISHED"}
    assert ob.boxmarch.sdf == "USER"
    text = blender.data.texts[ob.boxmarch.user_text].as_string()
    path = tmp_path / "template.frag"
    path.write_text(blender_declarations("frag") + shader_sources.fragment_source("USER", text))
    proc = subprocess.run([shutil.which("glslangValidator"), str(path)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout

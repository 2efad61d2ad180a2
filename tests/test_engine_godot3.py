"""Proof in a real engine: the GODOT3 preset's .glb and box table imported unmodified by Debian's
Godot 3.2 (headless import, compression off as its report asks). The test decodes the arrays
Godot stored with the documented formula (docs/ENGINES.md) against the generating geometry, then
Godot renders the shipped shader (shaders/godot3/boxmarch.shader) under xvfb and the pixels must
cover each box's projected silhouette within 1 px; a frame replaced by the identity must fail."""

import numpy as np
import pytest

from tests.engine_scene import (MIXED_SHAPES, TO_Y_UP, baked_scene, box_of_vertex, decode_normal_frame,
                                frame_and_size_errors, paint_shapes, per_box_agreement, rounded_box_mismatch, silhouettes,
                                table_texels)
from tests.engines import coverage_mismatch, godot3, import_helpers
from tests.helpers.preview_render import EXACT_MARCH
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Godot 3 imports and renders

W, H = 320, 240
WIDE = {"position": [2.0, 9.0, 14.0], "target": [0.5, -0.5, 0.0], "fov": 50, "near": 0.5, "far": 100}
INNER = 0.6


@pytest.fixture
def imported(blender, tmp_path):
    need(godot3.available())
    ob, centres, sizes, rotations = baked_scene(blender)
    boxes = paint_shapes(blender, ob, MIXED_SHAPES)
    path = tmp_path / "mixed.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GODOT3") == {"FINISHED"}
    table = (tmp_path / "mixed.boxes.tres").read_text()
    project = tmp_path / "project"
    godot3.import_gltf(path.read_bytes(), str(project), compress=False,
                       extra_files={"model.boxes.tres": table.encode()})
    return str(project), table, centres, sizes, rotations, boxes


def assert_decodes_to_the_boxes(surface, table, centres, sizes, rotations):
    """The NORMAL_COLOR decode (docs/ENGINES.md) of what Godot stored lands on the generating
    boxes: origin and half-extents within 1e-5, axes within 1e-6, one index per box."""
    box = box_of_vertex(surface["vertex"], centres, sizes, rotations, TO_Y_UP)
    colour = surface["color"]
    index = colour[:, 3]
    assert np.array_equal(index, np.rint(index))
    half = table_texels(table)[index.astype(int), :3]
    origins, axes, half = decode_normal_frame(surface["vertex"], surface["normal"], surface["tangent"],
                                              colour[:, :3], half)
    errors = frame_and_size_errors(origins, axes, half, box, centres, sizes, rotations, TO_Y_UP)
    assert errors[0] < 1e-5 and errors[1] < 1e-6 and errors[2] < 1e-5, errors
    assert sorted(set(index)) == list(range(len(centres)))
    for b in range(len(centres)):
        assert len(set(index[box == b])) == 1
    return errors


def origin_error(surface, centres, sizes, rotations):
    """Worst distance, over the box's largest half-extent, from a vertex's decoded origin to its
    generating box's centre (no use of the box table: it holds for any stored colour)."""
    box = box_of_vertex(surface["vertex"], centres, sizes, rotations, TO_Y_UP)
    origins, _axes, _half = decode_normal_frame(surface["vertex"], surface["normal"], surface["tangent"],
                                                surface["color"][:, :3], np.ones((len(box), 3)))
    centre = centres[box] @ TO_Y_UP.T
    return float((np.linalg.norm(origins - centre, axis=1) / (sizes[box].max(axis=1) / 2)).max())


def test_godot3_keeps_every_channel_and_decodes_to_the_boxes(imported):
    project, table, centres, sizes, rotations, _boxes = imported
    (surface,) = godot3.dump_arrays(project)
    assert_decodes_to_the_boxes(surface, table, centres, sizes, rotations)


def shader(frame_code=None):
    return godot3.shipped_shader("return sd_box(p, 0.6 * h);", frame_code)


def test_godot3_renders_each_box_at_its_own_size_and_the_negative_control_fails(imported):
    project, _table, centres, sizes, rotations, _boxes = imported
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    shot = godot3.render(project, shader(), width=W, height=H, camera=WIDE, uniforms=uniforms)
    covered = shot.pixels[..., :3].max(axis=2) > 20
    expected = silhouettes(shot, centres, INNER * sizes, rotations, TO_Y_UP)
    mismatch = coverage_mismatch(covered, expected)
    assert mismatch is None, mismatch
    assert covered.sum() > 500
    wrong = godot3.render(project, shader(godot3.IDENTITY_FRAME), width=W, height=H, camera=WIDE, uniforms=uniforms)
    assert coverage_mismatch(wrong.pixels[..., :3].max(axis=2) > 20, expected) is not None
    # the quality knob at 0.5 (secant steps within a quarter of a pixel, steps by size on screen): the
    # same silhouettes within 1 px
    knob = godot3.render(project, shader(), width=W, height=H, camera=WIDE, uniforms={**uniforms, "quality": 0.5})
    assert coverage_mismatch(knob.pixels[..., :3].max(axis=2) > 20, expected) is None


SHIPPED_ALBEDO = "  ALBEDO = base_color.rgb * (0.35 + 0.65 * max(n.z, 0.0));"


def marched_steps(project, uniforms):
    """(H, W) map() evaluations per pixel Godot ran (0 where nothing was drawn): the shipped
    shader with its colour replaced by its step count / 255, which Godot writes sRGB-encoded."""
    code = shader()
    assert SHIPPED_ALBEDO in code
    shot = godot3.render(project, code.replace(SHIPPED_ALBEDO, "  ALBEDO = vec3(float(steps) / 255.0);"), width=W,
                         height=H, camera=WIDE, uniforms=uniforms)
    encoded = shot.pixels[..., 0].astype(np.float64) / 255.0
    linear = np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)
    return np.rint(linear * 255.0)


def test_godot3_quality_knob_cuts_the_marching_steps(imported):
    """The quality knob measured in Godot: at 0.5 the boxes take fewer map() evaluations than at
    1 (the full march), in total and in no pixel more. Negative control: the knob under a
    misspelled uniform name (Godot ignores it) leaves the steps as they were, and is caught."""
    project, _table, _centres, _sizes, _rotations, _boxes = imported
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    full = marched_steps(project, uniforms)
    knob = marched_steps(project, {**uniforms, "quality": 0.5})
    ignored = marched_steps(project, {**uniforms, "qualty": 0.5})
    drawn = (full > 0) & (knob > 0)
    assert drawn.sum() > 500
    print(f"map() evaluations over {drawn.sum()} pixels: {full[drawn].sum():.0f} at quality 1, "
          f"{knob[drawn].sum():.0f} at 0.5, {ignored[drawn].sum():.0f} under a misspelled name")
    assert knob[drawn].sum() < 0.8 * full[drawn].sum()
    assert np.all(knob[drawn] <= full[drawn] + 2)  # 8-bit sRGB: 2 steps of rounding near 255
    assert not ignored[drawn].sum() < 0.8 * full[drawn].sum()


def test_godot3_shipped_shader_raymarches_a_rounded_box_of_each_box_own_size(imported):
    """The shipped shader as it is (sd_round_box of the box's own half-extents, radius 0.1 x the
    smallest): every covered pixel within 1 px of its box, every pixel of the box's core covered;
    with every box given the first box's half-extents (a table of one size) the check fails."""
    project, table, centres, sizes, rotations, _boxes = imported
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    code = godot3.shipped_shader()
    shot = godot3.render(project, code, width=W, height=H, camera=WIDE, uniforms=uniforms)
    covered = shot.pixels[..., :3].max(axis=2) > 20
    mismatch = rounded_box_mismatch(covered, shot, centres, sizes, rotations, TO_Y_UP)
    assert mismatch is None, mismatch
    one_size = code.replace("texelFetch(box_table, ivec2(i % size.x, i / size.x), 0).xyz", "texelFetch(box_table, ivec2(0, 0), 0).xyz")
    assert one_size != code
    wrong = godot3.render(project, one_size, width=W, height=H, camera=WIDE, uniforms=uniforms)
    assert rounded_box_mismatch(wrong.pixels[..., :3].max(axis=2) > 20, wrong, centres, sizes, rotations,
                                TO_Y_UP) is not None

# Each box the preset its shape id picks, the id read from the box table's plane 1 (docs/ENGINES.md).
PER_BOX_MAP = ("vec4 params = texelFetch(box_table, ivec2(bm_box_table_texel(index, 1.0, vec2(textureSize(box_table, 0)))), 0);\n"
               "return bm_sdf_by_id(params.x, p, h);")


def test_godot3_draws_the_shape_each_box_id_picks(imported):
    """The shipped shader with map() drawing each box's painted shape id, read from the box
    table (plane 1, bm_box_table_texel): coverage matches the CPU reference drawing the same ids
    on >= 99.5% of pixels; against the ids shuffled (rolled by one box) it must not."""
    project, _table, _centres, _sizes, _rotations, boxes = imported
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    shot = godot3.render(project, godot3.shipped_shader(PER_BOX_MAP), width=W, height=H, camera=WIDE, uniforms=uniforms)
    covered = shot.pixels[..., :3].max(axis=2) > 20
    agree = per_box_agreement(covered, shot, WIDE, boxes, MIXED_SHAPES)
    shuffled = per_box_agreement(covered, shot, WIDE, boxes, np.roll(MIXED_SHAPES, 1))
    assert covered.sum() > 500
    assert agree >= 0.995 and shuffled < 0.99, (agree, shuffled)


PER_BOX_CLOSED_FORM = ("vec4 params = texelFetch(box_table, ivec2(bm_box_table_texel(index, 1.0, "
                       "vec2(textureSize(box_table, 0)))), 0);\nreturn bm_preset_hit(params.x, ro, rd, h);")


def test_godot3_solves_each_box_shape_in_closed_form(imported):
    """bm_map_hit() giving each box's preset hit in closed form (bm_preset_hit of its shape id):
    coverage matches the CPU reference marched to the exact surface on >= 99.5 % of pixels;
    against the ids shuffled it must not."""
    project, _table, _centres, _sizes, _rotations, boxes = imported
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    code = godot3.shipped_shader(PER_BOX_MAP, closed_code=PER_BOX_CLOSED_FORM)
    shot = godot3.render(project, code, width=W, height=H, camera=WIDE, uniforms=uniforms)
    covered = shot.pixels[..., :3].max(axis=2) > 20
    agree = per_box_agreement(covered, shot, WIDE, boxes, MIXED_SHAPES, **EXACT_MARCH)
    shuffled = per_box_agreement(covered, shot, WIDE, boxes, np.roll(MIXED_SHAPES, 1), **EXACT_MARCH)
    assert covered.sum() > 500
    assert agree >= 0.995 and shuffled < 0.99, (agree, shuffled)


def test_godot3_eye_inside_a_shape_sees_it_everywhere_at_a_depth_in_range(imported):
    """The eye at the centre of box 6 (5 units across, painted SPHERE), looking at the other
    boxes: every pixel's ray starts inside the sphere, which hits at once at the eye, where the
    hit's clip w is 0. The depth written is the near end (0), never z / 0: the shader probed to
    paint white where the depth it writes lies in [0, 1] is white everywhere, and the same probe
    on the depth written as z / w unguarded (the negative control) is not. The picture: the
    sphere's inside hides every other box, and its shade (normal -ray) depends on the ray's angle
    to the view axis alone: the same turned half a turn about the view's centre, brightest there."""
    project, _table, centres, _sizes, _rotations, _boxes = imported
    assert MIXED_SHAPES[6] == 1  # SPHERE
    eye = TO_Y_UP @ centres[6]
    inside = {"position": eye.tolist(), "target": [0.0, 0.0, 0.0], "fov": 50, "near": 0.01, "far": 100}
    uniforms = {"box_table": "res://model.boxes.tres", "max_steps": 256}
    code = godot3.shipped_shader(PER_BOX_MAP, closed_code=PER_BOX_CLOSED_FORM)
    guarded = "bm_hit_depth(0.5 + 0.5 * clip.z / clip.w, clip.w, 0.0, true)"
    shade = "ALBEDO = base_color.rgb * (0.35 + 0.65 * max(n.z, 0.0));"
    assert code.count(f"DEPTH = {guarded};") == 1 and code.count(shade) == 1

    def grey(shader_code):
        return godot3.render(project, shader_code, width=W, height=H, camera=inside,
                             uniforms=uniforms).pixels[..., :3].astype(int).max(axis=2)

    def in_range(depth):
        """The share of pixels where the probed shader writes a depth in [0, 1]."""
        probed = code.replace(f"DEPTH = {guarded};", f"float written = {depth};\n  DEPTH = written;")
        return (grey(probed.replace(shade, "ALBEDO = vec3(written >= 0.0 && written <= 1.0 ? 1.0 : 0.0);")) > 128).mean()

    picture = grey(code)
    same = (np.abs(picture - picture[::-1, ::-1]) <= 2).mean()
    assert same >= 0.995 and (picture > 20).all() and picture[H // 2, W // 2] > picture[0, 0] + 10, same
    assert in_range(guarded) == 1.0
    assert in_range("0.5 + 0.5 * clip.z / clip.w") < 0.5


def test_godot3_default_compression_error_is_what_the_report_states(blender, tmp_path):
    """Godot's default import (mesh compression on) quantizes the colour to clamped 8 bits and the
    frame to 8-bit snorm: the decode breaks, and the export report says by how much."""
    need(godot3.available())
    from boxmarch.export import scene as export_scene

    ob, centres, sizes, rotations = baked_scene(blender)
    report = export_scene.export_objects(blender.context, [ob], "GODOT3", str(tmp_path / "mixed.glb"))
    assert "Compress off" in export_scene.import_note(report) and report["warnings"] == []
    project = tmp_path / "project"
    godot3.import_gltf((tmp_path / "mixed.glb").read_bytes(), str(project), compress=True)
    (surface,) = godot3.dump_arrays(str(project))
    error = origin_error(surface, centres, sizes, rotations)
    stated = report["default_import_error"]
    # Measured against the generating boxes, Godot's error is the report's figure (worst over
    # vertices against the float32 decode, from the measured quantization) within 1 %; far from
    # float precision (negative offsets clamp to 0: a box corner misses by sqrt(3) half-extents).
    assert error > 0.1
    assert stated is not None and abs(error - stated) <= 0.01 * stated, (error, stated)


def copied_project(project, folders, plugin=False):
    """A fresh Godot project holding the files of ``folders`` ({folder in the project: local
    folder}) as they are, with the boxmarch plug-in (engines/godot3/addons) enabled if asked."""
    files = {f"{name}/{p.name}": p.read_bytes() for name, folder in folders.items() for p in folder.iterdir()}
    if plugin:
        files.update({f"addons/boxmarch/{p.name}": p.read_bytes() for p in import_helpers.GODOT3_ADDON.iterdir()})
    godot3.write_project(str(project), files, ["boxmarch"] if plugin else ())
    return str(project)


@pytest.mark.slow
def test_godot3_export_folder_copied_alone_imports_float_exact(blender, tmp_path):
    """The GODOT3 export's folder copied as it is into a fresh project: Godot honours the
    NAME.glb.import written beside the .glb (compression off) and the decode is float-exact. The
    same folder without that file gets Godot's default import, which misses by over 0.1."""
    need(godot3.available())
    from boxmarch.export import scene as export_scene

    ob, centres, sizes, rotations = baked_scene(blender)
    export = tmp_path / "export"
    export.mkdir()
    export_scene.export_objects(blender.context, [ob], "GODOT3", str(export / "mixed.glb"))
    assert sorted(p.name for p in export.iterdir()) == ["mixed.boxes.tres", "mixed.boxmarch.json", "mixed.glb",
                                                        "mixed.glb.import"]
    project = copied_project(tmp_path / "project", {"models": export})
    godot3.import_project(project, ["models/mixed.glb"])
    (surface,) = godot3.dump_arrays(project, "res://models/mixed.glb")
    assert_decodes_to_the_boxes(surface, (export / "mixed.boxes.tres").read_text(), centres, sizes, rotations)
    (export / "mixed.glb.import").unlink()
    default = copied_project(tmp_path / "default", {"models": export})
    godot3.import_project(default, ["models/mixed.glb"])
    (surface,) = godot3.dump_arrays(default, "res://models/mixed.glb")
    assert origin_error(surface, centres, sizes, rotations) > 0.1


@pytest.mark.slow
def test_godot3_plugin_imports_boxmarch_glbs_float_exact_and_refuses_other_layouts(blender, tmp_path):
    """engines/godot3/addons/boxmarch enabled in a fresh project holding a GODOT3 export without
    its .import file (Godot's first import compresses it; the plug-in sets compression off and
    has it imported again) and a GLTF export (NORMAL_FRAME: its UV3-4 do not survive Godot 3's
    importer), both with their sidecars: the first decodes float-exact, the second is reported
    by name and layout and left as Godot imported it."""
    need(godot3.available())
    from boxmarch.export import scene as export_scene

    ob, centres, sizes, rotations = baked_scene(blender)
    godot, gltf = tmp_path / "godot", tmp_path / "gltf"
    godot.mkdir(), gltf.mkdir()
    export_scene.export_objects(blender.context, [ob], "GODOT3", str(godot / "mixed.glb"))
    (godot / "mixed.glb.import").unlink()
    export_scene.export_objects(blender.context, [ob], "GLTF", str(gltf / "other.glb"))
    project = copied_project(tmp_path / "project", {"models": godot, "other": gltf}, plugin=True)
    log = godot3.import_project(project, ["models/mixed.glb", "other/other.glb"], quiet_s=2.0)  # the re-import too
    (surface,) = godot3.dump_arrays(project, "res://models/mixed.glb")
    assert_decodes_to_the_boxes(surface, (godot / "mixed.boxes.tres").read_text(), centres, sizes, rotations)
    assert "boxmarch: re-importing res://models/mixed.glb with mesh compression off" in log
    assert ('boxmarch: res://other/other.boxmarch.json: preset must be "GODOT3", not "GLTF" (layout "NORMAL_FRAME"): '
            "Godot 3 keeps two UV sets only" in log), log
    assert "meshes/compress=true" in (tmp_path / "project" / "other" / "other.glb.import").read_text()

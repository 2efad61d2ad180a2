"""The decode-vectors view for Unreal (engines/unreal/boxmarch_decode_vectors.py): the design's
"Decode vertex vectors" debug view as an editor Python script. Unreal cannot run here: the script
runs against the stub ``unreal`` module (tests/engines/unreal_stub.py, modelled from Unreal 5's
Python API reference), whose selected actor holds a real UNREAL export of the mixed scene as
Unreal's import stores it (modelled from its documentation under the settings boxmarch_import.py
sets: tests/engine_scene.py). The lines it draws are checked against the generating box centres;
negative controls: the quaternion read with x and w swapped, or y negated, must visibly fail."""
import runpy

import numpy as np
import pytest

from tests.engine_scene import UNREAL, UV_NAMES, baked_scene, box_of_vertex, imported
from tests.engines.import_helpers import REPO
from tests.engines.unreal_stub import Actor, ImportedStaticMesh, StaticMeshComponent, StaticMeshDescription, unreal_session
from tests.fbx_reader import read_fbx_geometry

pytestmark = pytest.mark.slow  # Blender's FBX exporter

SCRIPT = REPO / "engines" / "unreal" / "boxmarch_decode_vectors.py"
# The wrong quaternion channels: (q.x, q.y) and (q.z, q.w) as the stub's description hands them out.
CONTROLS = {"x-and-w-swapped": lambda uvs: {**uvs, 1: np.c_[uvs[2][:, 1], uvs[1][:, 1]], 2: np.c_[uvs[2][:, 0], uvs[1][:, 0]]},
            "y-negated": lambda uvs: {**uvs, 1: uvs[1] * [1.0, -1.0]}}


@pytest.fixture(scope="module")
def exported(bpy_module, tmp_path_factory):
    from tests.conftest import empty_scene

    blender = empty_scene(bpy_module)
    _ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path_factory.mktemp("unreal-vectors") / "mixed.fbx"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="UNREAL") == {"FINISHED"}
    positions, uvs = imported(read_fbx_geometry(path), UNREAL)
    assert len(uvs) == len(UV_NAMES)
    return positions, dict(enumerate(uvs, start=1)), centres, sizes, rotations


def run_view(positions, uvs, argv=(), source=None):
    """The script's main(argv) (``source``: its text changed; None: as shipped) with one selected
    actor holding the mesh: (exit status, session)."""
    script = {"__name__": "boxmarch_decode_vectors"}
    exec(compile(source or SCRIPT.read_text(), str(SCRIPT), "exec"), script)  # noqa: S102 (the shipped script)
    with unreal_session() as session:
        mesh = ImportedStaticMesh(StaticMeshDescription(positions, uvs))
        session.selected = [Actor("Mixed", StaticMeshComponent(mesh))]
        status = script["main"](list(argv))
    return status, session


def lines_of(session, colour):
    """(starts, ends) of the debug lines drawn in ``colour`` (RGBA)."""
    chosen = [(start, end) for start, end, c, _duration in session.lines if np.allclose(c, colour)]
    return np.array([s for s, _e in chosen]), np.array([e for _s, e in chosen])


def centre_miss(starts, ends, centres, sizes, rotations):
    """Per line, how far its end lies from its box's generating centre, over the box's largest half-extent."""
    box = box_of_vertex(starts, centres, sizes, rotations, UNREAL["to_engine"])
    centre = centres[box] @ UNREAL["to_engine"].T
    return np.linalg.norm(ends - centre, axis=1) / (sizes[box].max(axis=1) / 2 * UNREAL["scale"])


def test_corrected_vectors_meet_at_each_box_centre_and_raw_ones_do_not(exported):
    positions, uvs, centres, sizes, rotations = exported
    status, session = run_view(positions, uvs, ["12"])
    assert status == 0 and session.log == []
    script = runpy.run_path(str(SCRIPT), run_name="boxmarch_decode_vectors")
    assert len(session.lines) == 2 * len(positions) and {line[3] for line in session.lines} == {12.0}
    starts, ends = lines_of(session, script["CORRECTED_COLOR"])
    assert len(starts) == len(positions)
    miss = centre_miss(starts, ends, centres, sizes, rotations)
    assert miss.max() < 1e-5, miss.max()
    raw_starts, raw_ends = lines_of(session, script["RAW_COLOR"])
    assert np.array_equal(raw_starts, starts)
    assert np.allclose(raw_ends - raw_starts, np.c_[uvs[3], uvs[4][:, :1]])  # f as the channels store it
    assert np.median(centre_miss(raw_starts, raw_ends, centres, sizes, rotations)) > 0.1


@pytest.mark.parametrize("control", sorted(CONTROLS))
def test_a_wrong_quaternion_channel_visibly_fails_to_converge(exported, control):
    positions, uvs, centres, sizes, rotations = exported
    status, session = run_view(positions, CONTROLS[control](uvs))
    assert status == 0
    script = runpy.run_path(str(SCRIPT), run_name="boxmarch_decode_vectors")
    miss = centre_miss(*lines_of(session, script["CORRECTED_COLOR"]), centres, sizes, rotations)
    print(f"{control}: corrected vectors end {np.median(miss):.2f} half-extents from their box's centre (median)")
    assert np.median(miss) > 0.1, np.median(miss)


@pytest.mark.parametrize("right, wrong", [("get_vertex_instance_uv(", "get_vertex_instance_uvs("),
                                          ("unreal.SystemLibrary.draw_debug_line(", "unreal.SystemLibrary.draw_line("),
                                          ("unreal.VertexInstanceID(", "unreal.VertexInstanceId(")])
def test_a_misspelled_unreal_call_fails_against_the_stub(exported, right, wrong):
    positions, uvs, _centres, _sizes, _rotations = exported
    text = SCRIPT.read_text()
    assert right in text
    with pytest.raises(AttributeError):
        run_view(positions, uvs, source=text.replace(right, wrong))


def test_nothing_selected_or_a_bad_duration_draws_nothing_and_says_why(exported):
    positions, uvs, _centres, _sizes, _rotations = exported
    script = runpy.run_path(str(SCRIPT), run_name="boxmarch_decode_vectors")
    with unreal_session() as session:
        assert script["main"]([]) == 1
    assert session.lines == [] and session.log == [
        ("error", "boxmarch: select the actors of a boxmarch UNREAL import first: nothing drawn")]
    status, session = run_view(positions, uvs, ["soon"])
    assert status == 1 and session.lines == [] and session.log == [("error", "boxmarch: SECONDS must be a number, not 'soon'")]

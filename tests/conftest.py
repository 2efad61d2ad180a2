"""Shared fixtures. Blender (the ``bpy`` module) is imported lazily, once per process, and only by
tests that ask for the ``blender`` fixture; the core tests never import it.

Markers (scripts/blender_matrix.py selects with them): ``bpy``, the add-on under the bpy module
(given to every test that uses the ``blender`` fixture, unless it is marked ``blender_program``);
``blender_program``, the add-on inside Debian's Blender 3.4 program."""
import os
import sys
import tempfile
from pathlib import Path

import pytest

from tests.helpers.blender_program import BPY_PATH

if BPY_PATH:  # another release's bpy module (tests/helpers/blender_program.py)
    sys.path.insert(0, BPY_PATH)

_SANDBOX = tempfile.mkdtemp(prefix="boxmarch-tests-")
# Headless Blender writes caches and its config under these: keep them out of the real home.
os.environ["XDG_CACHE_HOME"] = os.path.join(_SANDBOX, "cache")
os.environ["XDG_CONFIG_HOME"] = os.path.join(_SANDBOX, "config")


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(items):
    for item in items:
        if "bpy_module" in item.fixturenames and item.get_closest_marker("blender_program") is None:
            item.add_marker(pytest.mark.bpy)


_exit_status = None


def pytest_sessionfinish(session, exitstatus):
    global _exit_status
    _exit_status = int(exitstatus)


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """bpy 4.2 and 4.5 (PyPI) segfault at interpreter exit once an add-on registered classes
    (exit 139 after every test ran): leave with pytest's own status, after its report."""
    from boxmarch.cli import bpy_module_crashes_at_exit

    if _exit_status is not None and bpy_module_crashes_at_exit():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status)


@pytest.fixture(scope="session")
def bpy_module():
    import bpy

    import boxmarch

    if BPY_PATH:
        assert Path(bpy.__file__).is_relative_to(BPY_PATH), f"{bpy.__file__} is not from BOXMARCH_BPY_PATH={BPY_PATH}"
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        boxmarch.register()
    return bpy


@pytest.fixture
def blender(bpy_module):
    """bpy with an empty scene and the add-on registered."""
    return empty_scene(bpy_module)


def empty_scene(bpy):
    """``bpy`` after emptying the scene, with the add-on registered (for module-scoped fixtures)."""
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        import boxmarch

        boxmarch.register()
    return bpy


def mesh_object(bpy, name, positions, edges, face_starts, face_sizes, corner_verts, select=True):
    """A new object linked to the scene whose mesh holds exactly these arrays."""
    from boxmarch import mesh_io

    mesh = mesh_io.new_mesh(name, positions, face_starts, face_sizes, corner_verts, edges=edges)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    if select:
        ob.select_set(True)
        bpy.context.view_layer.objects.active = ob
    return ob


@pytest.fixture(scope="module")
def package_parent(tmp_path_factory):
    """A folder holding only the installed boxmarch package: Blender's own Python must not see
    the rest of this Python's site-packages."""
    import boxmarch

    parent = tmp_path_factory.mktemp("blender_path")
    (parent / "boxmarch").symlink_to(Path(boxmarch.__file__).parent, target_is_directory=True)
    return parent


def random_boxes_object(bpy, name="Boxes", count=4, offset=0.0, select=True):
    """A mesh object of ``count`` random boxes (scenes.random_boxes, seed 3), moved by ``offset``."""
    import numpy as np

    from boxmarch import scenes

    (arrays, *_), = [scenes.random_boxes(count, seed=3, spread=5.0, size_range=(0.5, 1.5))]
    return mesh_object(bpy, name, arrays[0] + np.float32(offset), *arrays[1:], select=select)


@pytest.fixture
def baked_blend(blender, tmp_path):
    """``world.blend`` in tmp_path: four random boxes, baked; the session's scene is left empty."""
    bpy = blender
    random_boxes_object(bpy, "Baked")
    assert bpy.ops.boxmarch.bake() == {"FINISHED"}
    path = tmp_path / "world.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return path


def digest(path):
    """SHA-256 of a file's bytes: a file a refused command must leave as it was."""
    import hashlib

    return hashlib.sha256(path.read_bytes()).hexdigest()

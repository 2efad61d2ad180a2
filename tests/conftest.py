"""Shared fixtures. Blender (the ``bpy`` module) is imported lazily, once per process, and only by
tests that ask for the ``blender`` fixture; the core tests never import it."""
import os
import tempfile

import numpy as np
import pytest

_SANDBOX = tempfile.mkdtemp(prefix="boxmarch-tests-")
# Headless Blender writes caches and its config under these: keep them out of the real home.
os.environ["XDG_CACHE_HOME"] = os.path.join(_SANDBOX, "cache")
os.environ["XDG_CONFIG_HOME"] = os.path.join(_SANDBOX, "config")


@pytest.fixture(scope="session")
def bpy_module():
    import bpy

    import boxmarch

    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        boxmarch.register()
    return bpy


@pytest.fixture
def blender(bpy_module):
    """bpy with an empty scene and the add-on registered."""
    bpy = bpy_module
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        import boxmarch

        boxmarch.register()
    return bpy


def mesh_object(bpy, name, positions, edges, face_starts, face_sizes, corner_verts, select=True):
    """A new object linked to the scene whose mesh holds exactly these arrays."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.asarray(positions, np.float32).reshape(-1))
    mesh.edges.add(len(edges))
    mesh.edges.foreach_set("vertices", np.asarray(edges, np.int32).reshape(-1))
    mesh.loops.add(len(corner_verts))
    mesh.loops.foreach_set("vertex_index", np.asarray(corner_verts, np.int32))
    mesh.polygons.add(len(face_starts))
    mesh.polygons.foreach_set("loop_start", np.asarray(face_starts, np.int32))
    if bpy.app.version < (4, 0, 0):
        mesh.polygons.foreach_set("loop_total", np.asarray(face_sizes, np.int32))
    mesh.update(calc_edges=True)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    if select:
        ob.select_set(True)
        bpy.context.view_layer.objects.active = ob
    return ob

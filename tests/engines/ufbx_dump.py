"""Child process of tests/engines/fbx_libraries.py: reads an FBX file with ufbx (the loader of
Godot 4.3+) and writes what ufbx delivers as float64 arrays into a .npz.

    python3 ufbx_dump.py IN.fbx OUT.npz

Written per polygon corner of the first mesh, in the file's own axes and units (no conversion
asked of ufbx; ``axes`` and ``unit_meters`` say what the file declares): ``vertex``, ``position``,
``normal``, ``tangent``, ``bitangent`` (where the file has them), ``uv:NAME`` per UV set and
``uv_names``; every node's world matrix and parent (``world:NAME``, ``parent:NAME``); for a
skinned mesh the clusters (``cluster_bones``: each cluster's bone, ``vertices:BONE``,
``weights:BONE``, ``geometry_to_bone:BONE``) and ufbx's skinning at the bones' transforms in the
file (``skinned_*``, :func:`read_skinning`).

ufbx's Python objects can crash when the garbage collector or a dropped temporary frees them:
the collector stays off, every object read stays referenced, and the process leaves with
os._exit.
"""
import gc
import os
import sys

gc.disable()

import numpy as np  # noqa: E402
import ufbx  # noqa: E402

_KEEP = []  # every ufbx object read, alive until os._exit


def hold(obj):
    _KEEP.append(obj)
    return obj


def matrix(m):
    """ufbx.Matrix (columns c0..c3) as a 4 x 4 float64 array."""
    out = np.eye(4)
    out[:3, :] = np.array([m.c0, m.c1, m.c2, m.c3], np.float64).T
    return out


def per_corner(attribute):
    """(corners, n) float64 values of a ufbx vertex attribute, looked up through its indices."""
    hold(attribute)
    return np.asarray(hold(attribute.values), np.float64)[np.asarray(hold(attribute.indices), np.int64)]


def source_version():
    """ufbx's C version (major.minor.patch) from the extension's ``ufbx_source_version``."""
    import ctypes
    import glob

    library = glob.glob(os.path.join(os.path.dirname(ufbx.__file__), "_native*"))[0]
    packed = ctypes.c_uint32.in_dll(ctypes.CDLL(library), "ufbx_source_version").value
    return f"{packed // 1000000}.{packed // 1000 % 1000}.{packed % 1000}"


def read_mesh(mesh, out):
    out["vertex"] = np.asarray(hold(mesh.vertex_indices), np.int64)
    for name, attribute in (("position", mesh.vertex_position), ("normal", mesh.vertex_normal),
                            ("tangent", mesh.vertex_tangent), ("bitangent", mesh.vertex_bitangent)):
        if hold(attribute).exists:
            out[name] = per_corner(attribute)
    uv_sets = hold(mesh.uv_sets)
    names = []
    for k in range(len(uv_sets)):
        uv_set = hold(uv_sets[k])
        names.append(uv_set.name)
        out["uv:" + uv_set.name] = per_corner(uv_set.vertex_uv)
    out["uv_names"] = np.array(names)


def read_skin(skin, out):
    clusters = hold(skin.clusters)
    bones = []
    for k in range(len(clusters)):
        cluster = hold(clusters[k])
        bone = hold(cluster.bone_node).name
        bones.append(bone)
        out["vertices:" + bone] = np.asarray(hold(cluster.vertices), np.int64)
        out["weights:" + bone] = np.asarray(hold(cluster.weights), np.float64)
        out["geometry_to_bone:" + bone] = matrix(cluster.geometry_to_bone)
    out["cluster_bones"] = np.array(bones)


def read_skinning(mesh, skin, out):
    """ufbx's skinning of the mesh at the nodes' transforms in the file (evaluated at load:
    ``evaluate_skinning``): ``skinned_position`` as ufbx skins it; ``skinned_normal`` and
    ``skinned_tangent``, the file's normals and tangents moved by the same blend of ufbx's evaluated
    cluster matrices, which ``skinned_blend_position`` shows equal to ufbx's skinned positions.
    ufbx's own skinned normals are generated from the skinned surface (``generated_normals``: one
    smooth normal per control point), not the file's normals moved, so they carry no box frame."""
    out["skinned_is_local"] = np.array(mesh.skinned_is_local)
    out["skinned_generated_normals"] = np.array(mesh.generated_normals)
    out["skinned_position"] = per_corner(mesh.skinned_position)
    clusters = hold(skin.clusters)
    blend = np.zeros((mesh.num_vertices, 4, 4))
    for k in range(len(clusters)):
        cluster = hold(clusters[k])
        np.add.at(blend, np.asarray(hold(cluster.vertices), np.int64),
                  np.asarray(hold(cluster.weights), np.float64)[:, None, None] * matrix(cluster.geometry_to_world))
    m = blend[out["vertex"]]
    for name in ("normal", "tangent"):
        out["skinned_" + name] = np.einsum("nij,nj->ni", m[:, :3, :3], out[name])
    out["skinned_blend_position"] = np.einsum("nij,nj->ni", m[:, :3, :3], out["position"]) + m[:, :3, 3]


def read_nodes(scene, out):
    nodes = hold(scene.nodes)
    for k in range(len(nodes)):
        node = hold(nodes[k])
        parent = hold(node.parent)
        if parent is not None:
            out["world:" + node.name] = matrix(node.node_to_world)
            out["parent:" + node.name] = np.array(parent.name)


def main(source, target):
    scene = hold(ufbx.load_file(source, evaluate_skinning=True))
    settings = hold(scene.settings)
    axes = hold(settings.axes)
    out = {"ufbx_version": np.array(source_version()), "unit_meters": np.array(settings.unit_meters),
           "axes": np.array([int(axes.right), int(axes.up), int(axes.front)])}
    mesh = hold(hold(scene.meshes)[0])
    read_mesh(mesh, out)
    read_nodes(scene, out)
    skins = hold(mesh.skin_deformers)
    if len(skins):
        skin = hold(skins[0])
        read_skin(skin, out)
        read_skinning(mesh, skin, out)
    np.savez(target, **out)


if __name__ == "__main__":
    try:
        main(*sys.argv[1:])
        code = 0
    except Exception as error:  # reported to the parent through the exit status and stderr
        print(f"ufbx_dump: {type(error).__name__}: {error}", file=sys.stderr)
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)

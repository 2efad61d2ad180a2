"""FBX files read by the libraries engines load them with: ufbx (Godot 4.3+'s FBX loader; PyPI
``ufbx``) in a child process (``ufbx_dump.py``), and Assimp (Debian ``assimp-utils``) through
``assimp export IN.fbx OUT.assbin`` and a reader of that binary dump (float32, as Assimp holds
its data; Debian's pyassimp crashes on load and Assimp's JSON export rounds to 6 digits). Both
return what the library delivers, in the file's own axes and units: neither library is asked to
convert anything. Blender-free except :func:`write_posed_copy`.
"""
import importlib.util
import os
import shutil
import struct
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def ufbx_available():
    """None when ufbx is installed, else the reason (looked up, not imported: the reading runs in
    a child process)."""
    return None if importlib.util.find_spec("ufbx") else "ufbx is not installed (pip install ufbx)"


def assimp_available():
    """None when the ``assimp`` command line tool is on PATH, else the reason."""
    return None if shutil.which("assimp") else "Assimp's command line tool is not installed (assimp-utils)"


def read_with_ufbx(path, folder):
    """dict of what ufbx delivers from the FBX file ``path`` (``ufbx_dump.py`` lists the keys),
    read in a child process whose failure (or crash) raises here with its output."""
    target = os.path.join(folder, os.path.basename(path) + ".ufbx.npz")
    run = subprocess.run([sys.executable, os.path.join(HERE, "ufbx_dump.py"), str(path), target],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, f"ufbx_dump failed ({run.returncode}): {run.stdout}{run.stderr}"
    with np.load(target) as data:
        return {key: data[key] for key in data.files}


def assimp_version():
    """'MAJOR.MINOR' as ``assimp version`` prints it."""
    out = subprocess.run(["assimp", "version"], capture_output=True, text=True, timeout=30).stdout
    return next(line.split()[1] for line in out.splitlines() if line.startswith("Version"))


def read_with_assimp(path, folder):
    """The scene Assimp imports from the FBX file ``path``, from its binary dump: {"nodes": [(name,
    4 x 4 local transform, parent index or -1, mesh indices)], "meshes": [{"position", "normal",
    "tangent", "bitangent" (float64 (vertices, 3), as present), "uv" (list of (vertices, 2)),
    "colours", "faces" (list of index lists), "bones" {name: (offset 4 x 4, vertex ids,
    weights)}}]}."""
    target = os.path.join(folder, os.path.basename(path) + ".assbin")
    run = subprocess.run(["assimp", "export", str(path), target], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and os.path.exists(target), f"assimp export failed: {run.stdout}{run.stderr}"
    with open(target, "rb") as f:
        return read_assbin(f.read())


class _Reader:
    """Little-endian cursor over Assimp's binary dump (AssbinFileWriter.cpp, format 1.0)."""

    def __init__(self, data, at=0):
        self.data, self.at = data, at

    def take(self, fmt):
        values = struct.unpack_from("<" + fmt, self.data, self.at)
        self.at += struct.calcsize("<" + fmt)
        return values

    def uint(self):
        return self.take("I")[0]

    def string(self):
        length = self.uint()
        self.at += length
        return self.data[self.at - length:self.at].decode()

    def floats(self, count, width):
        out = np.frombuffer(self.data, "<f4", count * width, self.at).reshape(count, width).astype(np.float64)
        self.at += 4 * count * width
        return out

    def matrix(self):
        return self.floats(4, 4)  # aiMatrix4x4 is row-major: a1..a4 is the first row

    def chunk(self, magic):
        found, size = self.take("II")
        assert found == magic, f"assbin: chunk {found:#x} where {magic:#x} was expected"
        return self.at + size


NODE, MESH, BONE, SCENE = 0x123C, 0x1237, 0x123A, 0x1239


def _node(r, parent, nodes):
    end = r.chunk(NODE)
    name, transform = r.string(), r.matrix()
    children, meshes, metadata = r.take("III")
    index = len(nodes)
    nodes.append((name, transform, parent, list(r.take(f"{meshes}I"))))
    for _ in range(children):
        _node(r, index, nodes)
    r.at = end  # metadata (axis settings and the like): not read


def _mesh(r):
    end = r.chunk(MESH)
    _primitives, vertices, faces, bones, _material, components = r.take("IIIIII")
    mesh = {"uv": [], "colours": [], "bones": {}}
    for bit, names in ((0x1, ("position",)), (0x2, ("normal",)), (0x4, ("tangent", "bitangent"))):
        if components & bit:
            for name in names:
                mesh[name] = r.floats(vertices, 3)
    for n in range(8):
        if components & (0x10000 << n):
            mesh["colours"].append(r.floats(vertices, 4))
    for n in range(8):
        if components & (0x100 << n):
            dimensions = r.uint()
            assert dimensions == 2, f"UV channel {n} has {dimensions} components"
            mesh["uv"].append(r.floats(vertices, 3)[:, :2])
    index = "H" if vertices < 1 << 16 else "I"
    mesh["faces"] = []
    for _ in range(faces):
        (count,) = r.take("H")
        mesh["faces"].append(list(r.take(index * count)))
    for _ in range(bones):
        bone_end = r.chunk(BONE)
        name, (weights,), offset = r.string(), r.take("I"), r.matrix()
        pairs = np.frombuffer(r.data, np.dtype([("vertex", "<u4"), ("weight", "<f4")]), weights, r.at)
        mesh["bones"][name] = (offset, pairs["vertex"].astype(np.int64), pairs["weight"].astype(np.float64))
        r.at = bone_end
    r.at = end
    return mesh


def read_assbin(data):
    """Nodes and meshes of an uncompressed, unshortened Assimp binary dump (see
    :func:`read_with_assimp`)."""
    assert data[:19] == b"ASSIMP.binary-dump.", "not an Assimp binary dump"
    major, minor, _revision, _flags, shortened, compressed = struct.unpack_from("<IIIIHH", data, 44)
    assert (major, minor, shortened, compressed) == (1, 0, 0, 0), (major, minor, shortened, compressed)
    r = _Reader(data, 512)
    r.chunk(SCENE)
    _flags, meshes, _materials, _animations, _textures, _lights, _cameras = r.take("IIIIIII")
    nodes = []
    _node(r, -1, nodes)
    return {"nodes": nodes, "meshes": [_mesh(r) for _ in range(meshes)]}


def euler_xyz_degrees(rotation):
    """FBX's default rotation order (eEulerXYZ: x first, then y, then z, R = Rz Ry Rx) as the
    degrees a Model's Lcl Rotation holds; ``rotation`` 3 x 3, away from gimbal lock."""
    r = np.asarray(rotation, np.float64)
    return np.degrees([np.arctan2(r[2, 1], r[2, 2]), np.arcsin(-r[2, 0]), np.arctan2(r[1, 0], r[0, 0])])


def write_posed_copy(source, target, local_by_model):
    """Copy the binary FBX ``source`` to ``target`` with the named Models' local transforms
    replaced ({name: 4 x 4 rotation + translation, relative to the parent}) as Lcl Translation
    and Lcl Rotation: a pose for a loader to evaluate, skin and bind pose untouched. Written with
    the export's FBX container code (boxmarch.formats.fbx_container)."""
    from boxmarch.formats import fbx_container

    document = fbx_container.read(source)
    objects = next(node for node in document.nodes if node.name == b"Objects")
    posed = set()
    for model in objects.children:
        name = model.props[1].split(b"\x00\x01")[0].decode() if model.name == b"Model" else None
        if name not in local_by_model:
            continue
        local = np.asarray(local_by_model[name], np.float64)
        properties = model.child(b"Properties70")
        properties.children[:] = [p for p in properties.children
                                  if p.props[0] not in (b"Lcl Translation", b"Lcl Rotation")]
        for label, values in ((b"Lcl Translation", local[:3, 3]), (b"Lcl Rotation", euler_xyz_degrees(local[:3, :3]))):
            properties.children.append(fbx_container.Node(b"P", [label, label, b"", b"A", *map(float, values)],
                                                          b"SSSSDDD"))
        posed.add(name)
    assert posed == set(local_by_model), f"no Model named {sorted(set(local_by_model) - posed)}"
    fbx_container.write(target, document)

"""Raw numbers of an FBX file for the tests and the export benchmark, read with Blender's own
FBX parser (io_scene_fbx.parse_fbx: the container only, no axis or colour conversion), so what
the exporter wrote is seen as an engine's importer sees it. Needs ``bpy`` imported first."""
import numpy as np


def child(elem, name):
    return next(c for c in elem.elems if c.id == name)


def _corner_vectors(layer, data_name, index_name, corner_vertex):
    """(corners, 3) vectors of a normal, tangent or binormal layer element (ByPolygonVertex or
    ByVertice, Direct or IndexToDirect)."""
    mapping = child(layer, b"MappingInformationType").props[0]
    assert mapping in (b"ByPolygonVertex", b"ByVertice"), mapping
    vectors = np.array(child(layer, data_name).props[0]).reshape(-1, 3)
    if child(layer, b"ReferenceInformationType").props[0] == b"IndexToDirect":
        vectors = vectors[np.array(child(layer, index_name).props[0])]
    return vectors[corner_vertex] if mapping == b"ByVertice" else vectors


def read_fbx_geometry(path):
    """Per polygon corner of the file's first Geometry: "vertex" (index), "position" (float64),
    each UV map and colour layer by name (float64 (corners, 2 or 4)), "uv_maps" and "colours"
    (layer names in file order), "triangles" (int64 (T, 3) corner indices, each polygon as a
    fan), "normal" and the first "tangent" and "binormal" layers where
    the file has them (float64 (corners, 3)), "control_points" (the Vertices, (n, 3)), and
    "settings" (GlobalSettings properties)."""
    from io_scene_fbx import parse_fbx

    root, _version = parse_fbx.parse(str(path))
    geometry = child(child(root, b"Objects"), b"Geometry")
    corner_vertex = np.array(child(geometry, b"PolygonVertexIndex").props[0])
    ends = np.flatnonzero(corner_vertex < 0)  # a polygon's last corner is stored as ~vertex
    corner_vertex = np.where(corner_vertex < 0, ~corner_vertex, corner_vertex)
    starts = np.r_[0, ends[:-1] + 1]
    triangles = np.array([(s, s + k, s + k + 1) for s, e in zip(starts, ends) for k in range(1, e - s)], np.int64)
    control_points = np.array(child(geometry, b"Vertices").props[0]).reshape(-1, 3)
    out = {"vertex": corner_vertex, "uv_maps": [], "colours": [], "control_points": control_points,
           "position": control_points[corner_vertex], "triangles": triangles.reshape(-1, 3)}
    for name, element, data_name, index_name in (("normal", b"LayerElementNormal", b"Normals", b"NormalsIndex"),
                                                 ("tangent", b"LayerElementTangent", b"Tangents", None),
                                                 ("binormal", b"LayerElementBinormal", b"Binormals", None)):
        layer = next((e for e in geometry.elems if e.id == element and e.props[0] == 0), None)
        if layer is not None:
            out[name] = _corner_vectors(layer, data_name, index_name, corner_vertex)
    for layer in geometry.elems:
        if layer.id not in (b"LayerElementUV", b"LayerElementColor"):
            continue
        name = child(layer, b"Name").props[0].decode()
        assert child(layer, b"MappingInformationType").props[0] == b"ByPolygonVertex"
        assert child(layer, b"ReferenceInformationType").props[0] == b"IndexToDirect"
        data, index, width, kind = ((b"UV", b"UVIndex", 2, "uv_maps") if layer.id == b"LayerElementUV"
                                    else (b"Colors", b"ColorIndex", 4, "colours"))
        out[kind].append(name)
        out[name] = np.array(child(layer, data).props[0]).reshape(-1, width)[np.array(child(layer, index).props[0])]
    settings = child(child(root, b"GlobalSettings"), b"Properties70")
    out["settings"] = {p.props[0].decode(): p.props[-1] for p in settings.elems}
    return out


def _matrix(elem):
    """An FBX matrix (16 doubles, column-major as FBX stores them) as a 4 x 4 array."""
    return np.array(elem.props[0], np.float64).reshape(4, 4).T


def read_fbx_skin(path):
    """The file's skin: {bone name: {"indexes" (control points), "weights", "transform",
    "transform_link" (4 x 4)}} from every Deformer of class Cluster, each named by the bone
    Model connected to it (Connections, OO)."""
    from io_scene_fbx import parse_fbx

    root, _version = parse_fbx.parse(str(path))
    objects = child(root, b"Objects")
    names = {elem.props[0]: elem.props[1].split(b"\x00\x01")[0].decode() for elem in objects.elems
             if len(elem.props) > 1}
    clusters = {elem.props[0]: elem for elem in objects.elems if elem.id == b"Deformer" and elem.props[2] == b"Cluster"}
    bone_of_cluster = {c.props[2]: names[c.props[1]] for c in child(root, b"Connections").elems
                       if c.props[0] == b"OO" and c.props[2] in clusters and c.props[1] in names}
    return {bone_of_cluster[uid]: {"indexes": np.array(child(elem, b"Indexes").props[0]),
                                   "weights": np.array(child(elem, b"Weights").props[0]),
                                   "transform": _matrix(child(elem, b"Transform")),
                                   "transform_link": _matrix(child(elem, b"TransformLink"))}
            for uid, elem in clusters.items()}


def tree_differences(path_a, path_b, limit=20):
    """Where the two FBX files, each read with Blender's parser, differ: record names, type codes
    and values (arrays by type and bytes), as up to ``limit`` lines naming the record's path."""
    from io_scene_fbx import parse_fbx

    (root_a, version_a), (root_b, version_b) = parse_fbx.parse(str(path_a)), parse_fbx.parse(str(path_b))
    out = [] if version_a == version_b else [f"version {version_a} != {version_b}"]
    _differences(root_a, root_b, "", out, limit)
    return out[:limit]


def _differences(a, b, where, out, limit):
    where = f"{where}/{a.id.decode(errors='replace')}"
    if a.id != b.id or bytes(a.props_type) != bytes(b.props_type):
        out.append(f"{where}: {a.id} {bytes(a.props_type)} != {b.id} {bytes(b.props_type)}")
        return
    for k, (x, y) in enumerate(zip(a.props, b.props)):
        same = (x.typecode == y.typecode and x.tobytes() == y.tobytes() if hasattr(x, "typecode")
                else type(x) is type(y) and (x == y or repr(x) == repr(y)))  # nan
        if not same:
            out.append(f"{where} property {k}: {str(x)[:60]} != {str(y)[:60]}")
    if len(a.elems) != len(b.elems):
        out.append(f"{where}: {len(a.elems)} children != {len(b.elems)}")
    for x, y in zip(a.elems, b.elems):
        if len(out) >= limit:
            return
        _differences(x, y, where, out, limit)

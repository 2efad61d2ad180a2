"""Raw numbers of an FBX file for the tests and the export benchmark, read with Blender's own
FBX parser (io_scene_fbx.parse_fbx: the container only, no axis or colour conversion), so what
the exporter wrote is seen as an engine's importer sees it. Needs ``bpy`` imported first."""
import numpy as np


def read_fbx_geometry(path):
    """Per polygon corner of the file's first Geometry: "vertex" (index), "position" (float64),
    each UV map and colour layer by name (float64 (corners, 2 or 4)), "uv_maps" and "colours"
    (layer names in file order), and "settings" (GlobalSettings properties)."""
    from io_scene_fbx import parse_fbx

    root, _version = parse_fbx.parse(str(path))
    child = lambda elem, name: next(c for c in elem.elems if c.id == name)
    geometry = child(child(root, b"Objects"), b"Geometry")
    corner_vertex = np.array(child(geometry, b"PolygonVertexIndex").props[0])
    corner_vertex = np.where(corner_vertex < 0, ~corner_vertex, corner_vertex)
    out = {"vertex": corner_vertex, "uv_maps": [], "colours": [],
           "position": np.array(child(geometry, b"Vertices").props[0]).reshape(-1, 3)[corner_vertex]}
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

"""The design's "Decode vertex vectors" view in Unreal Editor (docs/ENGINES.md, *The decode-vectors
view*): for every selected actor whose static mesh came from a boxmarch UNREAL export (imported by
boxmarch_import.py), draws from every vertex of LOD 0 the raw baked vector f (UV3, UV4.x: box-local
numbers drawn as if they were local-space, light blue) and f turned by the box's quaternion
q = (UV1, UV2) (orange), as debug lines in the editor's world. The orange lines of each box meet at
the box's origin; where they do not, the import changed the data (boxmarch_import.py's settings).
Select the actors, then in the editor's Python console:

    py "PATH/engines/unreal/boxmarch_decode_vectors.py" [SECONDS]

(SECONDS: how long the lines stay, default 30.) Written from Unreal 5's Python API reference
(StaticMesh.get_static_mesh_description, StaticMeshDescription, SystemLibrary.draw_debug_line,
EditorActorSubsystem); it has never run in Unreal: boxmarch's tests run it against a model of
those calls (tests/engines/unreal_stub.py) fed a modelled import of a real UNREAL export.
"""
import sys

RAW_COLOR = (0.55, 0.8, 1.0, 1.0)
CORRECTED_COLOR = (1.0, 0.55, 0.1, 1.0)
# The UV channels of the UV_FRAME layout (docs/ENGINES.md) this view reads.
QUAT_XY, QUAT_ZW, OFFSET_XY, OFFSET_Z_INDEX = 1, 2, 3, 4


def rotate_vector(v, q):
    """q v q* for the unit quaternion q = (x, y, z, w): v + 2 cross(q.xyz, cross(q.xyz, v) + q.w v),
    the shaders' bm_rotate_vector."""
    (x, y, z), w = q[:3], q[3]
    cx = y * v[2] - z * v[1] + w * v[0]
    cy = z * v[0] - x * v[2] + w * v[1]
    cz = x * v[1] - y * v[0] + w * v[2]
    return (v[0] + 2.0 * (y * cz - z * cy), v[1] + 2.0 * (z * cx - x * cz), v[2] + 2.0 * (x * cy - y * cx))


def vertex_vectors(description):
    """[(position, raw f, corrected f)] for every vertex instance of a StaticMeshDescription, in the
    mesh's local space (centimetres): the UNREAL preset wrote 1 - v, which the import undid, so the
    UVs hold the numbers boxmarch computed."""
    import unreal

    out = []
    for i in range(description.get_vertex_instance_count()):
        instance = unreal.VertexInstanceID(i)
        p = description.get_vertex_position(description.get_vertex_instance_vertex(instance))
        uv = {k: description.get_vertex_instance_uv(instance, k) for k in (QUAT_XY, QUAT_ZW, OFFSET_XY, OFFSET_Z_INDEX)}
        q = (uv[QUAT_XY].x, uv[QUAT_XY].y, uv[QUAT_ZW].x, uv[QUAT_ZW].y)
        f = (uv[OFFSET_XY].x, uv[OFFSET_XY].y, uv[OFFSET_Z_INDEX].x)
        out.append(((p.x, p.y, p.z), f, rotate_vector(f, q)))
    return out


def draw(actors, seconds=30.0):
    """Draws the view of every actor of ``actors`` with a static mesh; returns how many it drew."""
    import unreal

    world = unreal.get_editor_subsystem(unreal.UnrealEditorSubsystem).get_editor_world()
    drawn = 0
    for actor in actors:
        component = actor.get_component_by_class(unreal.StaticMeshComponent)
        mesh = component.get_editor_property("static_mesh") if component else None
        if mesh is None:
            unreal.log_warning(f"boxmarch: {actor.get_actor_label()} has no static mesh: nothing drawn")
            continue
        transform = component.get_world_transform()
        for p, raw, corrected in vertex_vectors(mesh.get_static_mesh_description(0)):
            start = transform.transform_location(unreal.Vector(*p))
            for v, colour in ((raw, RAW_COLOR), (corrected, CORRECTED_COLOR)):
                end = transform.transform_location(unreal.Vector(p[0] + v[0], p[1] + v[1], p[2] + v[2]))
                unreal.SystemLibrary.draw_debug_line(world, start, end, unreal.LinearColor(*colour), seconds, 0.0)
        drawn += 1
    return drawn


def main(argv):
    import unreal

    try:
        seconds = float(argv[0]) if argv else 30.0
    except ValueError:
        unreal.log_error(f"boxmarch: SECONDS must be a number, not {argv[0]!r}")
        return 1
    actors = unreal.get_editor_subsystem(unreal.EditorActorSubsystem).get_selected_level_actors()
    if not draw(actors, seconds):
        unreal.log_error("boxmarch: select the actors of a boxmarch UNREAL import first: nothing drawn")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

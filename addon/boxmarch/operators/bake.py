"""boxmarch.bake: bake box frames of the selected meshes (Object Mode) or of the submeshes touched
by the selection (Edit Mode)."""
from __future__ import annotations

import time

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from .. import bake_job, core, edit_mode, mesh_io


def _axis_turn_items(_self, _context):
    return _AXIS_TURN_ITEMS


_AXIS_TURN_ITEMS = []


def _build_axis_turn_items():
    # Built once at registration: Blender keeps enum item strings only while Python holds them.
    _AXIS_TURN_ITEMS[:] = [(str(i), core.axis_turn_label(i),
                            "Local axes of the baked frame in terms of the derived one", i)
                           for i in range(24)]


# UI words of core.ORIGIN_MODES (the one list of them).
_ORIGIN_LABELS = {"BOUNDS": ("Bounds Centre", "Centre of the submesh's bounding box in its own frame"),
                  "MEAN": ("Vertex Mean", "Average of the submesh's vertex positions")}
_ORIGIN_ITEMS = [(mode, *_ORIGIN_LABELS[mode]) for mode in core.ORIGIN_MODES]
# UI words of core.ENCODINGS.
_ENCODING_LABELS = {"FLOAT_COLOR": ("Float", "32-bit float colour: exact decode"),
                    "BYTE_COLOR": ("8-bit", "Byte colour: smaller, decode limited by quantisation")}
_ENCODING_ITEMS = [(encoding, *_ENCODING_LABELS[encoding]) for encoding in core.ENCODINGS]
# UI words of core.HIERARCHY_RULES.
_HIERARCHY_LABELS = {
    "ATTRIBUTE": ("Attribute", "Parent box index from the 'boxmarch_parent' attribute (none: every box a root)"),
    "CONTAINMENT": ("Containment", "The smallest larger box holding the box's centre"),
    "CHAIN": ("Chain", "The nearest lower-numbered box (instances along a curve are numbered along it)"),
    "BONES": ("Bones", "The nearest box of the parent bone of the box's bone (its vertex group with the most "
              "weight; the Armature modifier's rig)")}
_HIERARCHY_ITEMS = [(rule, *_HIERARCHY_LABELS[rule]) for rule in core.HIERARCHY_RULES]


class BOXMARCH_OT_bake(bpy.types.Operator):
    """Bake each submesh's origin and orientation into vertex colour and two UV maps"""

    bl_idname = "boxmarch.bake"
    bl_label = "Bake Box Frames"
    bl_options = {"REGISTER", "UNDO"}

    angle_epsilon: FloatProperty(
        name="Angle Epsilon", subtype="ANGLE", default=core.ANGLE_EPSILON_DEFAULT, min=core.ANGLE_EPSILON_RANGE[0],
        max=core.ANGLE_EPSILON_RANGE[1],
        description="The second axis comes from the largest face at least this far from the first axis's plane")
    origin: EnumProperty(
        name="Origin", default=core.ORIGIN_MODES[0],
        items=_ORIGIN_ITEMS)
    encoding: EnumProperty(
        name="Colour", default=core.ENCODINGS[0],
        items=_ENCODING_ITEMS)
    domain: EnumProperty(
        name="Domain", default="POINT",
        items=[("POINT", "Vertex", "One colour per vertex"), ("CORNER", "Face Corner", "One colour per face corner")])
    axis_turn: EnumProperty(name="Axis Turn", items=_axis_turn_items,
                            description="Turn the derived frame by an axis-aligned rotation (offsets follow)")
    sort_axes_by_extent: BoolProperty(
        name="Sort Axes by Extent", default=False,
        description="Local X along the longest side, Z along the shortest, before the turn")
    use_cache: BoolProperty(name="Copy Cache", default=True,
                            description="Derive the frame once for translated, rotated or scaled copies")
    incremental: BoolProperty(name="Skip Unchanged", default=True,
                              description="Leave submeshes whose geometry has not changed since the last bake")
    hierarchy: EnumProperty(name="Parents", default=core.HIERARCHY_RULES[0], items=_HIERARCHY_ITEMS)
    random_seed: IntProperty(name="Random Seed", default=0, min=0, max=core.RANDOM_SEED_MAX,
                             description="Seed of each box's random value (stable while the box is unchanged)")

    @classmethod
    def poll(cls, context):
        return context.mode in {"OBJECT", "EDIT_MESH"}

    def draw(self, _context):
        layout = self.layout
        layout.use_property_split = True
        for name in ("origin", "angle_epsilon", "encoding", "domain", "axis_turn",
                     "sort_axes_by_extent", "use_cache", "incremental", "hierarchy", "random_seed"):
            layout.prop(self, name)

    def execute(self, context):
        in_mode = context.objects_in_mode_unique_data if context.mode == "EDIT_MESH" else context.selected_objects
        objects = [ob for ob in in_mode if ob.type == "MESH"]
        meshes = [ob.data for ob in mesh_io.one_object_per_mesh(objects)]
        if not meshes:
            self.report({"ERROR"}, "Select at least one mesh object to bake")
            return {"CANCELLED"}
        settings = mesh_io.BakeSettings(
            angle_epsilon=self.angle_epsilon, origin=self.origin, encoding=self.encoding,
            domain=self.domain, axis_turn=int(self.axis_turn), sort_axes_by_extent=self.sort_axes_by_extent,
            use_cache=self.use_cache, incremental=self.incremental, hierarchy=self.hierarchy,
            random_seed=self.random_seed)
        start = time.perf_counter()
        wm = context.window_manager
        wm.progress_begin(0, 2 * len(meshes))
        try:
            with edit_mode.object_mode(context) as edit:
                if edit:
                    # Multi-object Edit Mode: a mesh with nothing selected is left alone (as dedup,
                    # merge and select do); only when no mesh has a selected vertex is there nothing
                    # to bake.
                    meshes = [mesh for mesh in meshes if mesh_io.read_vertex_selection(mesh).any()]
                    if not meshes:
                        self.report({"ERROR"}, "Nothing baked: no vertex is selected")
                        return {"CANCELLED"}
                prepared = bake_job.bake_meshes(meshes, settings, selected_only=edit,
                                                progress=lambda step, _steps, _what: wm.progress_update(step))
        except mesh_io.BakeInputError as error:
            self.report({"ERROR"}, f"Nothing baked: {error}")
            return {"CANCELLED"}
        finally:
            wm.progress_end()
        text = summary([bake.report for bake in prepared], time.perf_counter() - start)
        warnings = mesh_io.modifier_warnings(objects) + bake_job.not_box_warnings([bake.report for bake in prepared])
        if warnings:
            self.report({"WARNING"}, text + ". WARNING: " + " ".join(warnings))
        else:
            self.report({"INFO"}, text)
        return {"FINISHED"}


def summary(reports, seconds) -> str:
    total = bake_job.report_totals(reports)
    channels = sorted({r["uv_channels"] for r in reports if "uv_channels" in r})
    text = (f"Baked {total['baked']} of {total['submeshes']} submeshes in {len(reports)} mesh(es), "
            f"{seconds:.3f} s: {total['cache_hits']} cache hits, {total['unchanged']} unchanged skipped, "
            f"{total['degenerate']} degenerate, worst decode error {total['max_relative_error']:.2g} of half-extent")
    if total["not_selected"]:
        text += f", {total['not_selected']} not selected"
    if channels:
        text += "; quaternion in UV channels " + ", ".join(f"{a} and {b}" for a, b in channels)
    return text


def menu_object(self, _context):
    self.layout.separator()
    self.layout.operator(BOXMARCH_OT_bake.bl_idname, icon="MOD_WIREFRAME")


classes = (BOXMARCH_OT_bake,)
menus = (("VIEW3D_MT_object", menu_object), ("VIEW3D_MT_edit_mesh", menu_object))

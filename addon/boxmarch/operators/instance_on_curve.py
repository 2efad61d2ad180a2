"""boxmarch.add_instance_on_curve: a Geometry Nodes group that places copies of an object along
a curve at a fixed spacing WITHOUT turning them (axis-aligned), realised into one mesh so the
UV packing and the bake can run on the result (apply it, or tick Convert to Mesh)."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, StringProperty

GROUP_NAME = "Boxmarch Instance On Curve"


def _new_socket(group, name, in_out, socket_type):
    if hasattr(group, "interface"):  # Blender 4.0+
        return group.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    return (group.inputs if in_out == "INPUT" else group.outputs).new(socket_type, name)


def _input_identifiers(group):
    if hasattr(group, "interface"):
        return {item.name: item.identifier for item in group.interface.items_tree
                if item.item_type == "SOCKET" and item.in_out == "INPUT"}
    return {socket.name: socket.identifier for socket in group.inputs}


def ensure_node_group():
    """The node group, built once per file (rebuilt if a same-named group of another kind exists)."""
    group = bpy.data.node_groups.get(GROUP_NAME)
    if group is not None and group.bl_idname == "GeometryNodeTree":
        return group
    group = bpy.data.node_groups.new(GROUP_NAME, "GeometryNodeTree")
    _new_socket(group, "Curve", "INPUT", "NodeSocketGeometry")
    _new_socket(group, "Instance", "INPUT", "NodeSocketObject")
    spacing = _new_socket(group, "Spacing", "INPUT", "NodeSocketFloat")
    spacing.default_value = 1.0
    spacing.min_value = 1e-6
    _new_socket(group, "Geometry", "OUTPUT", "NodeSocketGeometry")

    nodes, links = group.nodes, group.links
    group_in = nodes.new("NodeGroupInput")
    to_points = nodes.new("GeometryNodeCurveToPoints")
    to_points.mode = "LENGTH"
    info = nodes.new("GeometryNodeObjectInfo")
    info.transform_space = "ORIGINAL"  # the instance's own geometry, not where it stands
    instance = nodes.new("GeometryNodeInstanceOnPoints")
    realize = nodes.new("GeometryNodeRealizeInstances")
    group_out = nodes.new("NodeGroupOutput")
    for x, node in enumerate((group_in, to_points, info, instance, realize, group_out)):
        node.location = (x * 220 - 600, 0 if node is not info else -250)
    links.new(group_in.outputs["Curve"], to_points.inputs["Curve"])
    links.new(group_in.outputs["Spacing"], to_points.inputs["Length"])
    links.new(group_in.outputs["Instance"], info.inputs["Object"])
    # The points' Rotation output stays unconnected: instances keep the world axes.
    links.new(to_points.outputs["Points"], instance.inputs["Points"])
    links.new(info.outputs["Geometry"], instance.inputs["Instance"])
    links.new(instance.outputs["Instances"], realize.inputs["Geometry"])
    links.new(realize.outputs["Geometry"], group_out.inputs["Geometry"])
    return group


class BOXMARCH_OT_add_instance_on_curve(bpy.types.Operator):
    """Place axis-aligned copies of an object along the active curve (Geometry Nodes group "Boxmarch Instance On Curve")"""

    bl_idname = "boxmarch.add_instance_on_curve"
    bl_label = "Instance on Curve (Axis-Aligned)"
    bl_options = {"REGISTER", "UNDO"}

    instance: StringProperty(name="Instance", default="",
                             description="Object to place along the curve (empty: the other selected object)")
    spacing: FloatProperty(name="Spacing", default=1.0, min=1e-6, soft_max=100.0, subtype="DISTANCE",
                           description="Distance along the curve between copies")
    convert_to_mesh: BoolProperty(name="Convert to Mesh", default=False,
                                  description="Apply the result into a mesh object, ready for UV packing and the bake")

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT" and context.active_object is not None

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop_search(self, "instance", bpy.data, "objects")
        layout.prop(self, "spacing")
        layout.prop(self, "convert_to_mesh")

    def execute(self, context):
        curve = context.active_object
        if curve.type != "CURVE":
            self.report({"ERROR"}, f"Active object '{curve.name}' is not a curve")
            return {"CANCELLED"}
        if not self.instance:
            others = [ob for ob in context.selected_objects if ob != curve]
            if not others:
                self.report({"ERROR"}, "Choose an Instance object (or select it besides the curve)")
                return {"CANCELLED"}
            self.instance = others[0].name
        instance = bpy.data.objects.get(self.instance)
        if instance is None:
            self.report({"ERROR"}, f"No object named '{self.instance}'")
            return {"CANCELLED"}
        if instance == curve:
            self.report({"ERROR"}, "The curve cannot be placed along itself")
            return {"CANCELLED"}
        copies, vertices = planned_size(curve, instance, self.spacing)
        if copies > MAX_COPIES or vertices > MAX_VERTICES:
            self.report({"ERROR"}, f"Spacing {self.spacing:g} would create {copies:,} copies ({vertices:,} vertices) "
                        f"along '{curve.name}': the limit is {MAX_COPIES:,} copies and {MAX_VERTICES:,} vertices; "
                        "raise the spacing")
            return {"CANCELLED"}
        group = ensure_node_group()
        # Running it again on the same curve updates its modifier instead of stacking another.
        modifier = next((m for m in curve.modifiers if m.type == "NODES" and m.node_group == group), None)
        if modifier is None:
            modifier = curve.modifiers.new(GROUP_NAME, "NODES")
            modifier.node_group = group
        ids = _input_identifiers(group)
        modifier[ids["Instance"]] = instance
        modifier[ids["Spacing"]] = float(self.spacing)
        curve.update_tag()
        context.view_layer.update()
        if self.convert_to_mesh:
            for ob in context.selected_objects:
                ob.select_set(ob == curve)
            bpy.ops.object.convert(target="MESH")
        self.report({"INFO"}, f"'{instance.name}' every {self.spacing:g} along '{curve.name}'"
                    + (", converted to a mesh" if self.convert_to_mesh else ""))
        return {"FINISHED"}


MAX_COPIES = 1_000_000
MAX_VERTICES = 50_000_000


def planned_size(curve, instance, spacing):
    """(copies, vertices) Curve to Points at ``spacing`` would make on ``curve`` (object space,
    each spline's evaluated length), checked before the node group allocates anything."""
    copies = 0
    for spline in curve.data.splines:
        length = spline.calc_length()
        copies += int(length / max(spacing, 1e-6)) + 1 if length > 0 else 0
    data = getattr(instance, "data", None)
    per_copy = len(data.vertices) if hasattr(data, "vertices") else 1
    return copies, copies * max(per_copy, 1)


def menu_add(self, _context):
    self.layout.separator()
    self.layout.operator(BOXMARCH_OT_add_instance_on_curve.bl_idname, icon="CURVE_DATA")


classes = (BOXMARCH_OT_add_instance_on_curve,)
menus = (("VIEW3D_MT_object", menu_add),)

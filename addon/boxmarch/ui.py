"""The Boxmarch tab of the 3D viewport's sidebar."""
import bpy

from . import mesh_io
from .operators import tools
from .operators.bake import BOXMARCH_OT_bake
from .operators.instance_on_curve import BOXMARCH_OT_add_instance_on_curve


class BOXMARCH_PT_bake(bpy.types.Panel):
    bl_label = "Bake"
    bl_idname = "BOXMARCH_PT_bake"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Boxmarch"

    def draw(self, context):
        layout = self.layout
        layout.operator(BOXMARCH_OT_bake.bl_idname, icon="MOD_WIREFRAME")
        ob = context.active_object
        if ob is None or ob.type != "MESH":
            layout.label(text="Active object is not a mesh")
            return
        mesh = ob.data
        offset = mesh.color_attributes.get(mesh_io.OFFSET_ATTRIBUTE)
        if offset is None:
            layout.label(text="Not baked yet", icon="INFO")
            return
        names = [uv.name for uv in mesh.uv_layers]
        col = layout.column(align=True)
        col.label(text=f"{mesh_io.OFFSET_ATTRIBUTE}: {offset.data_type}, {offset.domain}")
        for name in (mesh_io.QUAT_XY_UV, mesh_io.QUAT_ZW_UV):
            col.label(text=f"{name}: UV channel {names.index(name)}" if name in names else f"{name}: missing")


class BOXMARCH_PT_submesh_tools(bpy.types.Panel):
    bl_label = "Submesh Tools"
    bl_idname = "BOXMARCH_PT_submesh_tools"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Boxmarch"

    def draw(self, context):
        col = self.layout.column(align=True)
        for cls in tools.classes:
            col.operator(cls.bl_idname)
        self.layout.operator(BOXMARCH_OT_add_instance_on_curve.bl_idname, icon="CURVE_DATA")


classes = (BOXMARCH_PT_bake, BOXMARCH_PT_submesh_tools)

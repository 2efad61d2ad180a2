"""The Boxmarch tab of the 3D viewport's sidebar."""
import textwrap

import bpy

from .formats import layouts
from . import mesh_io
from .preview import skinning
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


class BOXMARCH_PT_preview(bpy.types.Panel):
    bl_label = "Raymarch Preview"
    bl_idname = "BOXMARCH_PT_preview"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Boxmarch"

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def draw_header(self, context):
        self.layout.prop(context.active_object.boxmarch, "preview", text="")

    def draw(self, context):
        from .preview import draw as preview_draw

        ob = context.active_object
        settings = ob.boxmarch
        layout = self.layout
        layout.use_property_split = True
        layout.active = settings.preview
        layout.prop(settings, "sdf")
        layout.prop(settings, "engine")
        layout.prop(settings, "layout")
        if not layouts.LAYOUTS[settings.layout].skin_safe and skinning.armature_modifier(ob) is not None:
            layout.label(text="Frame in UVs: stays in the rest pose when bones move", icon="INFO")
        if settings.sdf == "PER_BOX_BLEND":
            layout.prop(settings, "blend_radius")
        if settings.sdf == "USER":
            row = layout.row(align=True)
            row.prop_search(settings, "user_text", bpy.data, "texts")
            row.operator("boxmarch.new_sdf_text", text="", icon="FILE_NEW")
        layout.prop(settings, "quality", slider=True)
        col = layout.column(align=True)
        col.prop(settings, "max_steps")
        col.prop(settings, "epsilon")
        col.prop(settings, "relaxation")
        col.prop(settings, "max_distance")
        col = layout.column(heading="Show")
        col.prop(settings, "show_outline")
        col.prop(settings, "colour_by_material")
        col.prop(settings, "show_vectors")
        error = preview_draw.errors.get(ob.name)
        if settings.preview and error:
            box = layout.box()
            box.alert = True
            # wrapped to the sidebar's width (about 9 pixels per character at UI scale 1)
            chars = int(context.region.width / (9 * context.preferences.view.ui_scale)) - 4
            lines = textwrap.wrap(error, max(16, chars))
            for i, line in enumerate(lines[:6]):
                box.label(text=line, icon="ERROR" if i == 0 else "BLANK1")


classes = (BOXMARCH_PT_bake, BOXMARCH_PT_submesh_tools, BOXMARCH_PT_preview)

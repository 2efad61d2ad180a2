"""boxmarch.preview_toggle: switch the raymarch preview of the selected meshes on or off."""
import bpy

from .. import mesh_io


class BOXMARCH_OT_preview_toggle(bpy.types.Operator):
    """Draw the selected baked meshes raymarched in the 3D viewport (or stop)"""

    bl_idname = "boxmarch.preview_toggle"
    bl_label = "Toggle Raymarch Preview"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT" and any(ob.type == "MESH" for ob in context.selected_objects)

    def execute(self, context):
        meshes = [ob for ob in context.selected_objects if ob.type == "MESH"]
        enable = not all(ob.boxmarch.preview for ob in meshes)
        for ob in meshes:
            ob.boxmarch.preview = enable
        unbaked = sum(mesh_io.OFFSET_ATTRIBUTE not in ob.data.color_attributes for ob in meshes)
        text = f"Raymarch preview {'on' if enable else 'off'} for {len(meshes)} object(s)"
        if enable and unbaked:
            text += f"; {unbaked} not baked yet (drawn as outlines until baked)"
        self.report({"WARNING"} if enable and unbaked else {"INFO"}, text)
        return {"FINISHED"}


def menu_object(self, _context):
    self.layout.operator(BOXMARCH_OT_preview_toggle.bl_idname, icon="SHADING_RENDERED")


classes = (BOXMARCH_OT_preview_toggle,)
menus = (("VIEW3D_MT_object", menu_object),)

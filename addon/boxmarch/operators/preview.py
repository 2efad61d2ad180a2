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
        keyed = [warning for warning in (mesh_io.shape_key_warning(ob, "preview") for ob in meshes) if warning] \
            if enable else []
        if keyed:
            text += ". WARNING: " + " ".join(keyed)
        self.report({"WARNING"} if enable and (unbaked or keyed) else {"INFO"}, text)
        return {"FINISHED"}


SDF_TEMPLATE = """\
// boxmarch user SDF: box-local p (origin at the submesh's origin, axes the baked frame);
// box_half = the box's half-extents. The library of shaders/glsl/sdf.glsl is available
// (sd_*, op_*, min3, max3, sdf_preset_*); see docs/PREVIEW.md.
float map(vec3 p)
{
  float r = 0.25 * min3(box_half);
  float shell = sd_round_box(p, box_half - vec3(r), r);
  float hole = sd_cylinder(p, 0.5 * min(box_half.x, box_half.y), 2.0 * box_half.z);
  return op_smooth_subtract(shell, hole, 0.5 * r);
}
"""


class BOXMARCH_OT_new_sdf_text(bpy.types.Operator):
    """New text block with a template 'float map(vec3 p)', used as the active object's SDF"""

    bl_idname = "boxmarch.new_sdf_text"
    bl_label = "New SDF Text"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context):
        text = bpy.data.texts.new("boxmarch_sdf.glsl")
        text.write(SDF_TEMPLATE)
        settings = context.active_object.boxmarch
        settings.user_text = text.name
        settings.sdf = "USER"
        self.report({"INFO"}, f"SDF text '{text.name}' created; edit it in the Text Editor")
        return {"FINISHED"}


def menu_object(self, _context):
    self.layout.operator(BOXMARCH_OT_preview_toggle.bl_idname, icon="SHADING_RENDERED")


classes = (BOXMARCH_OT_preview_toggle, BOXMARCH_OT_new_sdf_text)
menus = (("VIEW3D_MT_object", menu_object),)

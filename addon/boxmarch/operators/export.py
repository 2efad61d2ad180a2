"""boxmarch.export: write the selected baked meshes for an engine (File > Export), with the
baked offsets and quaternions re-expressed in the engine's object frame (docs/EXPORT.md)."""
from __future__ import annotations

import os

import bpy
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ..formats import layouts
from ..export import scene
from ..formats import presets


class BOXMARCH_OT_export(bpy.types.Operator, ExportHelper):
    """Export the selected baked meshes with the box frames converted for an engine"""

    bl_idname = "boxmarch.export"
    bl_label = "Export Box Frames"
    bl_options = {"REGISTER", "PRESET"}

    filename_ext = ""  # set per preset in check()
    filter_glob: StringProperty(default="*.fbx;*.glb;*.blend", options={"HIDDEN"})
    preset: EnumProperty(
        name="Engine", default="UNITY",
        items=[(p.name, p.label, p.description) for p in presets.PRESETS.values()])
    layout: EnumProperty(
        name="Layout", default="DEFAULT",
        items=[("DEFAULT", "Preset's Own", "The layout the engine's importer carries best (docs/ENGINES.md)")]
        + [(layout.name, layout.label, layout.description) for layout in layouts.LAYOUTS.values()],
        description="Which vertex channels carry the box data")

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def check(self, _context):
        wanted = presets.PRESETS[self.preset].extension
        root, ext = os.path.splitext(self.filepath)
        if ext.lower() != wanted:
            self.filepath = (root if ext.lower() in {".fbx", ".glb", ".blend"} else self.filepath) + wanted
            return True
        return False

    def execute(self, context):
        self.check(context)
        layout = None if self.layout == "DEFAULT" else self.layout
        if not run_export(self, context, self.preset, self.filepath, layout):
            return {"CANCELLED"}
        # Remembered on the scene (saved with the .blend) for Quick Export.
        context.scene[LAST_EXPORT] = {"preset": self.preset, "filepath": self.filepath, "layout": self.layout}
        return {"FINISHED"}


LAST_EXPORT = "boxmarch_last_export"


def run_export(operator, context, preset, filepath, layout=None) -> bool:
    """Export the selected meshes and report in the status bar; False when nothing was written."""
    objects = [ob for ob in context.selected_objects if ob.type == "MESH"]
    wm = context.window_manager
    wm.progress_begin(0, 1)
    try:
        report = scene.export_objects(context, objects, preset, filepath, layout)
    except scene.ExportInputError as error:
        operator.report({"ERROR"}, f"Nothing exported: {error}")
        return False
    finally:
        wm.progress_end()
    for warning in report["warnings"]:
        operator.report({"WARNING"}, warning)
    channels = sorted({tuple(m.get("uv_channels", ())) for m in report["meshes"]} - {()})
    text = (f"Exported {len(report['objects'])} object(s) for {presets.PRESETS[preset].label} "
            f"({report['layout']}) to {report['path']} in {report['seconds']:.2f} s")
    if channels:
        text += "; box data in UV channels " + ", ".join(", ".join(map(str, c)) for c in channels)
    if report["table"]:
        text += f"; box table {report['table']}"
    if report["import_settings"]:
        operator.report({"INFO"}, f"Import settings: {scene.import_note(report)}")
    operator.report({"INFO"}, text)
    return True


class BOXMARCH_OT_quick_export(bpy.types.Operator):
    """Export the selected baked meshes again with the last engine preset and file (no dialog)"""

    bl_idname = "boxmarch.quick_export"
    bl_label = "Quick Export Box Frames"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def invoke(self, context, _event):
        if LAST_EXPORT not in context.scene:  # first time: ask where, like the full exporter
            return bpy.ops.boxmarch.export("INVOKE_DEFAULT")
        return self.execute(context)

    def execute(self, context):
        last = context.scene.get(LAST_EXPORT)
        if last is None or last.get("preset") not in presets.PRESETS:
            self.report({"ERROR"}, "Nothing exported yet in this scene: use File > Export > Boxmarch Box Frames first")
            return {"CANCELLED"}
        layout = last.get("layout", "DEFAULT")
        return ({"FINISHED"} if run_export(self, context, last["preset"], last["filepath"],
                                           None if layout == "DEFAULT" else layout) else {"CANCELLED"})


def menu_export(self, _context):
    self.layout.operator(BOXMARCH_OT_export.bl_idname, text="Boxmarch Box Frames (.fbx/.glb/.blend)")
    self.layout.operator(BOXMARCH_OT_quick_export.bl_idname, text="Boxmarch Quick Export (last preset and file)")


classes = (BOXMARCH_OT_export, BOXMARCH_OT_quick_export)
menus = (("TOPBAR_MT_file_export", menu_export),)

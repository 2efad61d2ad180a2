# boxmarch: bake box-local frames into meshes for raymarching inside rasterized boxes.
# Copyright (C) 2026 the boxmarch developers. SPDX-License-Identifier: GPL-3.0-or-later
"""boxmarch: a Blender add-on and a Blender-free NumPy API (``boxmarch.core``).

Importing the package does not import ``bpy``; ``register()`` does, when Blender loads the add-on.
"""

bl_info = {
    "name": "Boxmarch",
    "author": "boxmarch developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Boxmarch; Object and Edit Mesh menus",
    "description": "Bake per-submesh origins and frames for raymarching inside rasterized boxes",
    "category": "Mesh",
}

_registered = []


class NativeModuleMissing(ModuleNotFoundError):
    """boxmarch's native module (_core) is not built: its message says how to build it (raised by
    boxmarch.native; here, where the command line can catch it without importing that module)."""


def register():
    import bpy

    from . import operators, preview, properties, ui

    operators.register_enums()
    for cls in operators.classes + properties.classes + ui.classes:
        bpy.utils.register_class(cls)
        _registered.append(cls)
    properties.register_properties()
    preview.register()
    for menu_name, draw in operators.menus:
        getattr(bpy.types, menu_name).append(draw)


def ensure_registered():
    """Register the add-on unless it is registered already (scripts and the command line, which
    import the package without Blender loading it as an add-on)."""
    import bpy

    if not hasattr(bpy.types, "BOXMARCH_OT_bake"):
        register()


def unregister():
    import bpy

    from . import operators, preview, properties

    preview.unregister()
    properties.unregister_properties()
    for menu_name, draw in operators.menus:
        getattr(bpy.types, menu_name).remove(draw)
    while _registered:
        bpy.utils.unregister_class(_registered.pop())

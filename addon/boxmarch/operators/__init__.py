"""Blender operators: thin shells over boxmarch.mesh_io and boxmarch.core."""
from . import bake, instance_on_curve, preview, tools

classes = bake.classes + tools.classes + instance_on_curve.classes + preview.classes
menus = bake.menus + tools.menus + instance_on_curve.menus + preview.menus


def register_enums():
    bake._build_axis_turn_items()

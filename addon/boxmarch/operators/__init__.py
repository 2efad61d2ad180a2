"""Blender operators: thin shells over boxmarch.mesh_io and boxmarch.core."""
from . import bake, preview

classes = bake.classes + preview.classes
menus = bake.menus + preview.menus


def register_enums():
    bake._build_axis_turn_items()

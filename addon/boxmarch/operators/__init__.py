"""Blender operators: thin shells over boxmarch.mesh_io and boxmarch.core."""
from . import bake, export

classes = bake.classes + export.classes
menus = bake.menus + export.menus


def register_enums():
    bake._build_axis_turn_items()

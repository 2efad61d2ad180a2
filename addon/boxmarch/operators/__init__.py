"""Blender operators: thin shells over boxmarch.mesh_io and boxmarch.core."""
from . import bake

classes = bake.classes
menus = bake.menus


def register_enums():
    bake._build_axis_turn_items()

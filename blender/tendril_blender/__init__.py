"""Tendril for Blender: grow climbing, L-system and component-graph plants on your meshes with
Tendril's Python module, and animate them in the wind.  See docs/blender.md."""

bl_info = {
    "name": "Tendril",
    "author": "Tendril authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar (N) > Tendril",
    "description": "Grow ivy, L-system and component-graph plants on the selected objects; wind animation",
    "category": "Add Mesh",
}

if "bpy" in locals():  # F8 / reload scripts
    import importlib
    for _m in (backend, convert, build, scene_doc, wind, operators, ui):  # noqa: F821
        importlib.reload(_m)
else:
    from . import backend, convert, build, scene_doc, wind, operators, ui

import bpy
from bpy.props import PointerProperty

_classes = ui.classes + operators.classes


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.tendril = PointerProperty(type=ui.TendrilSceneSettings)


def unregister():
    del bpy.types.Scene.tendril
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)

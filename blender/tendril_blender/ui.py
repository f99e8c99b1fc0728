"""Preferences, scene settings and the 3D view sidebar panel (tab "Tendril")."""

import json

import bpy
from bpy.props import IntProperty, StringProperty

from . import backend, build, scene_doc


def _module_path_changed(self, context):
    backend.reset()


class TendrilPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    module_path: StringProperty(
        name="Module Path", subtype='DIR_PATH', default="", update=_module_path_changed,
        description="Directory holding Tendril's 'tendril' Python package (e.g. <tendril>/build/ci/python), "
                    "used when 'import tendril' fails")
    threads: IntProperty(name="Threads", default=0, min=0, max=1024,
                         description="Worker threads for growth (0 = all cores); results do not depend on it")

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "module_path")
        layout.prop(self, "threads")
        draw_status(layout, verbose=True)


class TendrilSceneSettings(bpy.types.PropertyGroup):
    strokes_json: StringProperty(
        name="Attractor Strokes", default="", options={'HIDDEN'},
        description="Strokes stored by Paint Attractors (Tendril coordinates, scene-format JSON)")


def draw_status(layout, verbose=False):
    mod = backend.load()
    if mod is not None:
        layout.label(text=f"Tendril {backend.version()}", icon='CHECKMARK')
        return False
    box = layout.box()
    col = box.column(align=True)
    col.alert = True
    col.label(text="Tendril's Python module was not found", icon='ERROR')
    sub = box.column(align=True)
    sub.scale_y = 0.8
    sub.label(text="Set Preferences > Add-ons > Tendril > Module Path")
    sub.label(text="to the directory with the 'tendril' package")
    sub.label(text="(e.g. <tendril>/build/ci/python), or set")
    sub.label(text=f"{backend.ENV_VAR} before starting Blender.")
    if verbose:
        for line in backend.attempts():
            sub.label(text=line)
    box.operator("tendril.reload_module", icon='FILE_REFRESH', text="Reload")
    return True


class VIEW3D_PT_tendril(bpy.types.Panel):
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Tendril"
    bl_label = "Tendril"

    def draw(self, context):
        layout = self.layout
        missing = draw_status(layout)
        col = layout.column(align=True)
        col.enabled = not missing
        col.operator("tendril.grow_ivy", icon='OUTLINER_OB_CURVES' if hasattr(bpy.types, "Curves") else 'CURVE_DATA')
        col.operator("tendril.add_lsystem_plant", icon='OUTLINER_OB_FORCE_FIELD')
        col.operator("tendril.add_graph_plant", icon='OUTLINER_DATA_LIGHTPROBE')
        supports = scene_doc.support_objects(context)
        sub = layout.column(align=True)
        sub.scale_y = 0.8
        if supports:
            names = ", ".join(o.name for o in supports[:3]) + (" ..." if len(supports) > 3 else "")
            sub.label(text=f"Supports: {names}", icon='MESH_CUBE')
        else:
            sub.label(text="Supports: none selected", icon='INFO')
        c = context.scene.cursor.location
        sub.label(text=f"Cursor {c.x:.2f}, {c.y:.2f}, {c.z:.2f}", icon='PIVOT_CURSOR')


class VIEW3D_PT_tendril_attractors(bpy.types.Panel):
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Tendril"
    bl_label = "Attractors"
    bl_parent_id = "VIEW3D_PT_tendril"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = self.layout
        row = layout.row(align=True)
        row.operator("tendril.paint_attractors", icon='GREASEPENCIL')
        row.operator("tendril.clear_attractors", icon='X', text="")
        strokes = scene_doc.stored_strokes(context.scene)
        n = sum(len(s.get("points", [])) for s in strokes)
        kinds = sorted({s.get("kind", "attract") for s in strokes})
        text = f"{len(strokes)} stroke(s), {n} points ({', '.join(kinds)})" if strokes else "No strokes stored"
        layout.label(text=text)


class VIEW3D_PT_tendril_wind(bpy.types.Panel):
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Tendril"
    bl_label = "Wind"
    bl_parent_id = "VIEW3D_PT_tendril"

    def draw(self, context):
        layout = self.layout
        row = layout.row(align=True)
        row.enabled = backend.load() is not None
        row.operator("tendril.wind_animation", icon='FORCE_WIND')
        row.operator("tendril.clear_wind", icon='X', text="")


class VIEW3D_PT_tendril_plant(bpy.types.Panel):
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Tendril"
    bl_label = "Plant"
    bl_parent_id = "VIEW3D_PT_tendril"

    @classmethod
    def poll(cls, context):
        return build.is_tendril_object(context.view_layer.objects.active)

    def draw(self, context):
        layout = self.layout
        obj = context.view_layer.objects.active
        col = layout.column(align=True)
        col.label(text=f"{obj.get(build.PROP_PLANT, obj.name)} ({obj.get(build.PROP_MODEL, '?')})")
        try:
            doc = json.loads(obj[build.PROP_SCENE])
            plant = next((p for p in doc.get("plants", []) if p.get("name") == obj.get(build.PROP_PLANT)), {})
            what = plant.get("species") or plant.get("grammar") or plant.get("graph")
            if isinstance(what, str):
                col.label(text=f"From: {what}")
            col.label(text=f"Steps: {doc.get('steps')}  seed: {plant.get('seed', '-')}")
            col.label(text=f"Supports: {len(doc.get('environment', {}).get('obstacles', []))}")
        except (ValueError, AttributeError):
            col.label(text="(stored scene unreadable)")
        me = obj.data
        col.label(text=f"{len(me.vertices)} vertices, {len(me.polygons)} triangles")
        if obj.get(build.PROP_WIND):
            try:
                w = json.loads(obj[build.PROP_WIND])
                col.label(text=f"Wind: {w['frames']} frames from {w['frame_start']}", icon='FORCE_WIND')
            except (ValueError, KeyError):
                pass
        layout.operator("tendril.export_scene", icon='EXPORT')


classes = (
    TendrilPreferences,
    TendrilSceneSettings,
    VIEW3D_PT_tendril,
    VIEW3D_PT_tendril_attractors,
    VIEW3D_PT_tendril_wind,
    VIEW3D_PT_tendril_plant,
)

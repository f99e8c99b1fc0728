"""The add-on's operators (docs/blender.md).  Each one reports bad input with
self.report({'ERROR'}, ...) and returns {'CANCELLED'}; nothing escapes as a traceback."""

import json
import math
import os
import time
import traceback
import warnings

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ExportHelper
from mathutils import Vector

from . import backend, build, convert, scene_doc, wind
from .scene_doc import UserError

SOURCE = "blender"   # Session source name: errors read "blender:/plants/0/species: ..."

# --- dynamic enums ---------------------------------------------------------------------------
# Blender keeps only pointers to the strings of dynamic enum items: the lists must stay alive.
_enum_cache = {}


# Each model's default (docs/scene-format.md) comes first, so that it is the enum's default.
PREFERRED = {"climb": "japanese-ivy", "particles": "ivy-particles", "lsystem": "japanese-ivy", "graph": "sunflower"}


def preset_label(name):
    """presets('graph') may list paths: show their file names."""
    base = os.path.basename(name.replace("\\", "/"))
    return os.path.splitext(base)[0] if base.lower().endswith((".json", ".ls")) else base


def ordered_presets(model):
    names = backend.presets(model)
    preferred = [n for n in names if preset_label(n) == PREFERRED.get(model)]
    return preferred + [n for n in names if n not in preferred]


def preset_items(model, what):
    names = ordered_presets(model)
    items = [(n, preset_label(n), f"Tendril's built-in {what} {n}") for n in names]
    if not items:
        items = [("NONE", "(no presets: Tendril module not loaded)", "")]
    if _enum_cache.get(model) != items:
        _enum_cache[model] = items
    return _enum_cache[model]


def _species_items(self, context):
    return preset_items(getattr(self, "model", "climb") or "climb", "species")


def _grammar_items(self, context):
    return preset_items("lsystem", "grammar")


def _graph_items(self, context):
    return preset_items("graph", "graph")


def _addon_prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None


def _base_dir():
    if bpy.data.filepath:
        return os.path.dirname(bpy.path.abspath(bpy.data.filepath))
    return os.getcwd()


def _file_path(path, what):
    path = path.strip()
    if not path:
        raise UserError(f"Choose a {what} file (or a built-in preset)")
    return os.path.abspath(bpy.path.abspath(path))


# --- common machinery -------------------------------------------------------------------------

class _TendrilOperator:
    """execute() -> run(context, tendril) with errors reported, never raised."""

    _progress_on = False

    def execute(self, context):
        self._progress_on = False
        try:
            tendril = backend.require()
            return self.run(context, tendril)
        except backend.NotLoaded as e:
            self.report({'ERROR'}, str(e))
        except (UserError,) + backend.error_types() as e:
            self.report({'ERROR'}, str(e))
        except Exception as e:  # a bug (here or in the module): say so, never crash
            traceback.print_exc()
            self.report({'ERROR'}, f"Tendril add-on: unexpected {type(e).__name__}: {e} (details in the console)")
        finally:
            self._progress_end(context)
        return {'CANCELLED'}

    # progress in the status bar / cursor
    def _progress_begin(self, context, total):
        context.window_manager.progress_begin(0, max(1, total))
        self._progress_on = True

    def _progress_end(self, context):
        if self._progress_on:
            context.window_manager.progress_end()
            self._progress_on = False
        ws = getattr(context, "workspace", None)
        if ws is not None and context.area is not None:
            try:
                ws.status_text_set(None)
            except Exception:
                pass

    def _status(self, context, text):
        ws = getattr(context, "workspace", None)
        if ws is not None and context.area is not None:
            try:
                ws.status_text_set(text)
            except Exception:
                pass

    def _set_threads(self, context, tendril):
        prefs = _addon_prefs(context)
        if prefs is not None and hasattr(tendril, "set_threads"):
            tendril.set_threads(int(prefs.threads))

    def grow_session(self, context, tendril, doc, base_dir, what="growing"):
        """A Session for `doc`, run for the document's steps with progress. What Tendril warns
        about (a plant at its cap, an open support mesh) goes to Blender's report area."""
        self._set_threads(context, tendril)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # reported below, once each, rather than on stderr
            s = tendril.Session(doc, base_dir, SOURCE)
            steps = int(doc.get("steps", 0))
            if steps > 0:
                wm = context.window_manager
                self._progress_begin(context, steps)
                label = f"Tendril: {what}"

                def progress(done):
                    wm.progress_update(min(int(done), steps))
                    self._status(context, f"{label} step {done}/{steps}")

                s.run(steps, progress)
        for w in dict.fromkeys(getattr(s, "warnings", [])):
            self.report({'WARNING'}, f"Tendril: {w}")
        return s

    def finish_objects(self, context, objs):
        for o in context.selected_objects:
            if build.is_tendril_object(o):
                o.select_set(False)
        for o in objs:
            o.select_set(True)
        if objs:
            context.view_layer.objects.active = objs[0]


class _EnvironmentProps:
    """Supports, ground, lights, strokes and mesh resolution: shared by the growing operators."""

    use_ground: BoolProperty(
        name="Ground", default=False,
        description="Add a ground plane (a Tendril plane obstacle, 40 m across, under the 3D cursor) "
                    "to the supports")
    ground_height: FloatProperty(name="Ground Height", default=0.0, unit='LENGTH',
                                 description="Height (Z) of the ground plane")
    snap_to_surface: BoolProperty(
        name="Snap to Surface", default=True,
        description="Put each seed on the closest support surface (1 mm off it)")
    use_lights: BoolProperty(name="Scene Lights", default=True,
                             description="Sun, point, spot and area lights steer growth (phototropism)")
    use_strokes: BoolProperty(name="Painted Attractors", default=True,
                              description="Use the strokes stored by Paint Attractors")
    radial_segments: IntProperty(name="Radial Segments", default=8, min=3, max=64,
                                 description="Vertices around each branch")
    subdivisions: IntProperty(name="Subdivisions", default=3, min=1, max=16,
                              description="Spline samples per skeleton segment")

    def environment(self, context, require_support):
        objects = scene_doc.support_objects(context)
        cursor = context.scene.cursor.location.copy()
        ground = (cursor.x, cursor.y, self.ground_height) if self.use_ground else None
        supports = scene_doc.Supports(context, objects, ground)
        for w in supports.warnings:
            self.report({'WARNING'}, w)
        if require_support and not supports:
            raise UserError("Nothing to grow on: select one or more mesh objects as supports "
                            "(or enable Ground)")
        lights = scene_doc.lights(context) if self.use_lights else []
        strokes = scene_doc.stored_strokes(context.scene) if self.use_strokes else []
        return supports, lights, strokes

    def draw_environment(self, layout):
        col = layout.column(heading="Supports")
        col.prop(self, "snap_to_surface")
        row = col.row(align=True)
        row.prop(self, "use_ground")
        sub = row.row()
        sub.active = self.use_ground
        sub.prop(self, "ground_height", text="")
        col.prop(self, "use_lights")
        col.prop(self, "use_strokes")
        col = layout.column(align=True)
        col.prop(self, "radial_segments")
        col.prop(self, "subdivisions")


def _plant_from_seed(p, d):
    return convert.vec_to_tendril(p), convert.vec_to_tendril(d)


# --- Grow ivy ---------------------------------------------------------------------------------

class TENDRIL_OT_grow_ivy(_TendrilOperator, _EnvironmentProps, bpy.types.Operator):
    """Grow climbing plants over the selected objects, from the 3D cursor or scattered seeds"""
    bl_idname = "tendril.grow_ivy"
    bl_label = "Grow Ivy on Selected"
    bl_options = {'REGISTER', 'UNDO'}

    model: EnumProperty(
        name="Model",
        items=[("climb", "Climbing", "Seed 003's climbing growth: tips, rules, tropisms"),
               ("particles", "Particles", "Seed 000's oriented particles (physics steps of 25 ms)")],
        default="climb")
    species: EnumProperty(name="Species", items=_species_items,
                          description="Built-in species of the model")
    species_file: StringProperty(name="Species File", subtype='FILE_PATH', default="",
                                 description="A species .json (docs/species.md); overrides the preset")
    steps: IntProperty(name="Steps", default=150, min=0, max=1000000,
                       description="Growth steps (climbing: one internode per tip; particles: 25 ms "
                                   "physics steps, ~1000+); stops early when nothing grows")
    seed: IntProperty(name="Seed", default=1, min=0,
                      description="Random seed (the scene's, each plant's, and the scatter's)")
    placement: EnumProperty(
        name="Seeds",
        items=[("CURSOR", "3D Cursor", "Plants start at the 3D cursor (spread around it)"),
               ("SCATTER", "Scatter", "Plants start at random points on the selected surfaces")],
        default="CURSOR")
    plant_count: IntProperty(name="Plants", default=1, min=1, max=256)
    spread: FloatProperty(name="Spread", default=0.5, min=0.0, soft_max=10.0, unit='LENGTH',
                          description="3D cursor seeds: radius around the cursor for the 2nd, 3rd... plant")
    align_to_normal: BoolProperty(name="Grow Along Normal", default=True,
                                  description="Start growing along the surface normal (else straight up)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "model")
        layout.prop(self, "species")
        layout.prop(self, "species_file")
        col = layout.column(align=True)
        col.prop(self, "steps")
        col.prop(self, "seed")
        layout.prop(self, "placement", expand=True)
        col = layout.column(align=True)
        col.prop(self, "plant_count")
        if self.placement == 'CURSOR':
            sub = col.row()
            sub.active = self.plant_count > 1
            sub.prop(self, "spread")
        layout.prop(self, "align_to_normal")
        self.draw_environment(layout)

    def run(self, context, tendril):
        supports, lights, strokes = self.environment(context, require_support=True)
        if self.species_file.strip():
            species = _file_path(self.species_file, "species")
        else:
            names = ordered_presets(self.model)
            species = self.species if self.species in names else (names[0] if names else None)
        snap = self.snap_to_surface or self.placement == 'SCATTER'
        seeds = scene_doc.seed_points(supports, context.scene.cursor.location, self.placement,
                                      self.plant_count, self.spread, self.seed, snap, self.align_to_normal)
        prefix = os.path.splitext(os.path.basename(species))[0] if species else self.model
        plants = []
        for i, (p, d) in enumerate(seeds):
            pos, direction = _plant_from_seed(p, d)
            plant = {"name": f"{prefix}-{i + 1}" if len(seeds) > 1 else prefix, "model": self.model,
                     "position": convert.rounded(pos), "direction": convert.rounded(direction),
                     "seed": self.seed + i}
            if species:
                plant["species"] = species
            plants.append(plant)
        doc = scene_doc.document(self.seed, self.steps, supports.obstacles, [], self.radial_segments,
                                 self.subdivisions, lights, strokes)
        base_dir = _base_dir()
        if self.placement == 'SCATTER':
            plants = self._accepted(tendril, doc, base_dir, plants)
        doc["plants"] = plants
        return self.grow_and_build(context, tendril, doc, base_dir)

    def _accepted(self, tendril, doc, base_dir, plants):
        """Scattered seeds that Tendril refuses (inside another support, growing into one) are
        left out with a warning rather than failing the whole grow."""
        s = tendril.Session(dict(doc, plants=[]), base_dir, SOURCE)
        ok, first = [], None
        for p in plants:
            try:
                s.add_plant(p)
                ok.append(p)
            except backend.error_types() as e:
                first = first or e
                self.report({'WARNING'}, f"seed {p['name']} left out: {e}")
        if not ok:
            raise UserError(f"No scattered seed can grow: {first}")
        return ok

    def grow_and_build(self, context, tendril, doc, base_dir):
        t0 = time.perf_counter()
        s = self.grow_session(context, tendril, doc, base_dir)
        model = s.mesh()
        objs = build.build_objects(context, model, doc, base_dir, backend.version())
        if not objs:
            raise UserError("Nothing grew (no geometry): move the 3D cursor onto or next to a support, "
                            "or raise Steps")
        self.finish_objects(context, objs)
        steps = int(doc["steps"])
        if self.model == "climb" and steps >= 20 and s.step_count < steps // 4:
            self.report({'WARNING'}, f"Tendril: growth stopped after {s.step_count} of {steps} steps: a climber "
                                     "needs a support within reach (japanese-ivy: 8 cm) -- put the 3D cursor at "
                                     "the foot of a wall, or on it")
        self.report({'INFO'}, f"Tendril: {len(objs)} plant(s), {s.segment_count} segments in "
                              f"{s.step_count} steps ({time.perf_counter() - t0:.1f} s)")
        return {'FINISHED'}


# --- L-system and graph plants -----------------------------------------------------------------

class _PlaceProps:
    seed: IntProperty(name="Seed", default=1, min=0)
    align_to_normal: BoolProperty(name="Grow Along Normal", default=False,
                                  description="Start along the support's normal (else straight up)")
    scale: FloatProperty(name="Scale", default=1.0, min=1e-4, soft_max=10.0,
                         description="Object scale of the result (display only: growth is at "
                                     "full size against the supports)")

    def placed_plant(self, context, supports):
        cursor = context.scene.cursor.location
        snap = self.snap_to_surface and bool(supports)
        (p, d), = scene_doc.seed_points(supports, cursor, 'CURSOR', 1, 0.0, self.seed, snap,
                                        self.align_to_normal)
        pos, direction = _plant_from_seed(p, d)
        return {"position": convert.rounded(pos), "direction": convert.rounded(direction),
                "seed": int(self.seed)}


class TENDRIL_OT_add_lsystem_plant(_TendrilOperator, _EnvironmentProps, _PlaceProps, bpy.types.Operator):
    """Add an L-system plant (a built-in grammar or a .ls file) at the 3D cursor, growing
    against the selected objects"""
    bl_idname = "tendril.add_lsystem_plant"
    bl_label = "Add L-system Plant"
    bl_options = {'REGISTER', 'UNDO'}

    source: EnumProperty(name="Source", items=[("PRESET", "Preset", "A built-in grammar"),
                                              ("FILE", "File", "A grammar file (.ls, docs/grammar.md)")],
                         default="PRESET")
    grammar: EnumProperty(name="Grammar", items=_grammar_items)
    filepath: StringProperty(name="Grammar File", subtype='FILE_PATH', default="")
    derivation_length: IntProperty(name="Derivation Steps", default=0, min=0, max=100000,
                                   description="0 = the grammar's own 'derivation length'")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "source", expand=True)
        layout.prop(self, "grammar" if self.source == 'PRESET' else "filepath")
        col = layout.column(align=True)
        col.prop(self, "derivation_length")
        col.prop(self, "seed")
        layout.prop(self, "align_to_normal")
        layout.prop(self, "scale")
        self.draw_environment(layout)

    def run(self, context, tendril):
        supports, lights, strokes = self.environment(context, require_support=False)
        plant = self.placed_plant(context, supports)
        if self.source == 'FILE':
            grammar = _file_path(self.filepath, "grammar")
            name = os.path.splitext(os.path.basename(grammar))[0]
        else:
            grammar = self.grammar
            if grammar not in backend.presets("lsystem"):
                raise UserError(f"Unknown grammar preset '{grammar}'")
            name = preset_label(grammar)
        plant = dict({"name": name, "model": "lsystem", "grammar": grammar}, **plant)
        # Each Session step is one derivation step; the Session stops after the grammar's own
        # derivation length when it is not overridden.
        steps = 100000
        if self.derivation_length > 0:
            plant["derivation_length"] = int(self.derivation_length)
            steps = int(self.derivation_length)
        doc = scene_doc.document(self.seed, steps, supports.obstacles, [plant], self.radial_segments,
                                 self.subdivisions, lights, strokes)
        return _grow_placed(self, context, tendril, doc)


class TENDRIL_OT_add_graph_plant(_TendrilOperator, _EnvironmentProps, _PlaceProps, bpy.types.Operator):
    """Add a component-graph plant (a built-in graph or a graph .json) at the 3D cursor"""
    bl_idname = "tendril.add_graph_plant"
    bl_label = "Add Graph Plant"
    bl_options = {'REGISTER', 'UNDO'}

    source: EnumProperty(name="Source", items=[("PRESET", "Preset", "A built-in graph"),
                                              ("FILE", "File", "A graph file (.json, docs/graph-format.md)")],
                         default="PRESET")
    graph: EnumProperty(name="Graph", items=_graph_items)
    filepath: StringProperty(name="Graph File", subtype='FILE_PATH', default="")
    use_graph_seed: BoolProperty(name="Graph's Seed", default=True,
                                 description="Use the graph's own seed (else Seed)")
    overrides: StringProperty(name="Overrides", default="",
                              description='Parameter overrides as JSON, e.g. {"stalk/branches": 9}')

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "source", expand=True)
        layout.prop(self, "graph" if self.source == 'PRESET' else "filepath")
        layout.prop(self, "use_graph_seed")
        sub = layout.row()
        sub.active = not self.use_graph_seed
        sub.prop(self, "seed")
        layout.prop(self, "overrides")
        layout.prop(self, "align_to_normal")
        layout.prop(self, "scale")
        self.draw_environment(layout)

    def run(self, context, tendril):
        supports, lights, strokes = self.environment(context, require_support=False)
        plant = self.placed_plant(context, supports)
        if self.use_graph_seed:
            del plant["seed"]
        if self.source == 'FILE':
            graph = _file_path(self.filepath, "graph")
            name = os.path.splitext(os.path.basename(graph))[0]
        else:
            graph = self.graph
            if graph not in backend.presets("graph"):
                raise UserError(f"Unknown graph preset '{graph}'")
            name = preset_label(graph)
        plant = dict({"name": name, "model": "graph", "graph": graph}, **plant)
        if self.overrides.strip():
            try:
                overrides = json.loads(self.overrides)
            except ValueError as e:
                raise UserError(f"Overrides are not JSON: {e}")
            if not isinstance(overrides, dict):
                raise UserError('Overrides must be a JSON object, e.g. {"stalk/branches": 9}')
            plant["overrides"] = overrides
        # A graph plant is complete when the scene is read: no growth steps.
        doc = scene_doc.document(self.seed, 0, supports.obstacles, [plant], self.radial_segments,
                                 self.subdivisions, lights, strokes)
        return _grow_placed(self, context, tendril, doc)


def _grow_placed(op, context, tendril, doc):
    t0 = time.perf_counter()
    base_dir = _base_dir()
    s = op.grow_session(context, tendril, doc, base_dir)
    model = s.mesh()
    objs = build.build_objects(context, model, doc, base_dir, backend.version(), scale=op.scale)
    if not objs:
        raise UserError("The plant has no geometry")
    op.finish_objects(context, objs)
    op.report({'INFO'}, f"Tendril: {objs[0].name}: {len(objs[0].data.vertices)} vertices "
                        f"({time.perf_counter() - t0:.1f} s)")
    return {'FINISHED'}


# --- Wind animation ------------------------------------------------------------------------------

def _selected_plants(context):
    objs = [o for o in context.selected_objects if build.is_tendril_object(o)]
    active = context.view_layer.objects.active
    if not objs and build.is_tendril_object(active):
        objs = [active]
    return objs


class TENDRIL_OT_wind_animation(_TendrilOperator, bpy.types.Operator):
    """Animate the selected Tendril plants swaying in the wind: a looping clip of shape keys or a
    point cache"""
    bl_idname = "tendril.wind_animation"
    bl_label = "Wind Animation"
    bl_options = {'REGISTER', 'UNDO'}

    mode: EnumProperty(name="Wind", items=[("CONSTANT", "Constant", "The same wind everywhere"),
                                          ("GUSTY", "Gusty", "Gust fronts travelling downwind")],
                       default="GUSTY")
    speed: FloatProperty(name="Speed", default=3.0, min=0.0, max=200.0, unit='VELOCITY',
                         description="Prevailing wind speed (m/s). Above the species' wind_min (4 m/s by "
                                     "default, gusts included) the wind also changes growth: the plant is regrown")
    direction: FloatProperty(name="Direction", default=0.0, subtype='ANGLE',
                             description="Where the wind blows to, in the XY plane: 0 = +X, 90 = +Y")
    gust_strength: FloatProperty(name="Gust Strength", default=0.3, min=0.0, max=1.0,
                                 description="Fraction of the speed gusts add or take away")
    gust_period: FloatProperty(name="Gust Period", default=3.0, min=0.05, max=3600.0, unit='TIME_ABSOLUTE',
                               description="Seconds between independent gusts")
    gust_turn: FloatProperty(name="Gust Turn", default=math.radians(12.0), min=0.0,
                             max=math.radians(90.0), subtype='ANGLE',
                             description="How far gusts turn the wind about the vertical")
    wind_seed: IntProperty(name="Gust Seed", default=0, min=0)
    seconds: FloatProperty(name="Loop Length", default=4.0, min=0.1, max=600.0, unit='TIME_ABSOLUTE',
                           description="Length of the looping clip (s)")
    fps: IntProperty(name="Clip FPS", default=0, min=0, max=240,
                     description="Frames per second of the clip; 0 = the scene's frame rate")
    frame_start: IntProperty(name="Start Frame", default=1)
    method: EnumProperty(
        name="Store As",
        items=[("SHAPE_KEYS", "Shape Keys", "One shape key per frame, keyed: all in the .blend, exports to "
                                            "glTF/FBX as morph targets (frames x vertices x 12 bytes)"),
               ("MESH_CACHE", "Mesh Cache", "A PC2 point cache file (next to the .blend, in tendril_cache/) "
                                            "read by a Mesh Cache modifier: light for heavy plants")],
        default="SHAPE_KEYS")
    set_frame_range: BoolProperty(name="Set Frame Range", default=True,
                                  description="Set the scene's frame range to one loop")
    cyclic: BoolProperty(name="Cyclic", default=True,
                         description="Repeat the loop forever (Cycles F-curve modifiers)")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "mode", expand=True)
        col = layout.column(align=True)
        col.prop(self, "speed")
        col.prop(self, "direction")
        if self.mode == 'GUSTY':
            col = layout.column(align=True)
            col.prop(self, "gust_strength")
            col.prop(self, "gust_period")
            col.prop(self, "gust_turn")
            col.prop(self, "wind_seed")
        col = layout.column(align=True)
        col.prop(self, "seconds")
        col.prop(self, "fps")
        col.prop(self, "frame_start")
        layout.prop(self, "method")
        layout.prop(self, "set_frame_range")
        layout.prop(self, "cyclic")

    def wind(self):
        v = (self.speed * math.cos(self.direction), self.speed * math.sin(self.direction), 0.0)
        w = {"mode": self.mode.lower(), "velocity": convert.rounded(convert.vec_to_tendril(v))}
        if self.mode == 'GUSTY':
            w.update({"gust_strength": round(self.gust_strength, 6), "gust_period": round(self.gust_period, 6),
                      "gust_turn": round(math.degrees(self.gust_turn), 6), "seed": int(self.wind_seed)})
        return w

    def run(self, context, tendril):
        objs = _selected_plants(context)
        if not objs:
            raise UserError("Select plants grown by Tendril (Grow Ivy, Add L-system/Graph Plant)")
        scene = context.scene
        scene_fps = scene.render.fps / (scene.render.fps_base or 1.0)
        clip_fps = self.fps if self.fps > 0 else max(1, int(round(scene_fps)))
        frame_step = scene_fps / clip_fps
        wind_doc = self.wind()

        groups = {}
        for o in objs:
            groups.setdefault((o[build.PROP_SCENE], o.get(build.PROP_BASE_DIR, _base_dir())), []).append(o)
        t0 = time.perf_counter()
        rebuilt, caches, n_frames = [], [], 0
        for (text, base_dir), members in groups.items():
            try:
                doc = json.loads(text)
            except ValueError as e:
                raise UserError(f"{members[0].name}: its stored Tendril scene is not JSON ({e})")
            doc.setdefault("environment", {})["wind"] = wind_doc
            s = self.grow_session(context, tendril, doc, base_dir, "regrowing")
            model = s.mesh()
            self._status(context, "Tendril: computing wind frames")
            frames = wind.drop_closing_frame(list(s.wind_frames(float(self.seconds), int(clip_fps))),
                                             int(round(self.seconds * clip_fps)))
            if not frames:
                raise UserError("The module returned no wind frames")
            n_frames = len(frames)
            first_part = []
            count = 0
            for rec in model.objects:
                first_part.append(count)
                count += len(build.object_parts(rec))
            if any(len(f) != count for f in frames):
                raise UserError(f"wind_frames() returned {len(frames[0])} parts per frame, "
                                f"Session.mesh() has {count} (module bug)")
            materials = build.MaterialCache(model)
            new_text = json.dumps(doc, separators=(",", ":"))
            for obj in members:
                oi = int(obj.get(build.PROP_OBJECT, -1))
                if not 0 <= oi < len(model.objects):
                    raise UserError(f"{obj.name}: the regrown scene has no object {oi}")
                rec = model.objects[oi]
                rest = build.rest_positions(rec, obj.get(build.PROP_ORIGIN, (0.0, 0.0, 0.0)))
                if not _same_positions(obj, rest):
                    # Wind above the species' wind_min changes growth (Growth-Flow), or the mesh
                    # was edited: the rest shape is rebuilt from the regrown plant.
                    wind.clear(obj)
                    build.replace_mesh(obj, rec, materials)
                    rebuilt.append(obj.name)
                parts = range(first_part[oi], first_part[oi] + len(build.object_parts(rec)))
                posed = [wind.object_space(p, obj) for p in wind.object_frames(frames, parts)]
                if self.method == 'MESH_CACHE':
                    path, stored = _cache_path(obj)
                    wind.write_pc2(path, posed, clip_fps)
                    wind.animate_mesh_cache(obj, path, stored, len(posed), self.frame_start, frame_step, self.cyclic)
                    caches.append(path)
                else:
                    wind.animate(obj, posed, self.frame_start, frame_step, self.cyclic)
                obj[build.PROP_SCENE] = new_text
                obj[build.PROP_WIND] = json.dumps({"wind": wind_doc, "seconds": self.seconds, "fps": clip_fps,
                                                   "frame_start": self.frame_start, "frames": len(frames)})
        if self.set_frame_range:
            scene.frame_start = self.frame_start
            scene.frame_end = self.frame_start + max(1, int(round(n_frames * frame_step))) - 1
        if caches and not bpy.data.filepath:
            self.report({'WARNING'}, f"Tendril: the .blend is not saved: point caches went to {os.path.dirname(caches[0])} "
                                     "(temporary); save the file and run Wind Animation again to keep them")
        if rebuilt:
            self.report({'WARNING'}, f"Tendril: regrown in this wind (Growth-Flow changes growth above the "
                                     f"species' wind_min): new rest shape for {', '.join(rebuilt)}")
        self.report({'INFO'}, f"Tendril: {n_frames} wind frames on {len(objs)} object(s) "
                              f"({time.perf_counter() - t0:.1f} s)")
        return {'FINISHED'}


def _cache_path(obj):
    """(absolute path to write, path for the modifier) of the object's PC2 wind cache."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in obj.name)
    if bpy.data.filepath:
        stored = f"//tendril_cache/{safe}.pc2"
        return bpy.path.abspath(stored), stored
    path = os.path.join(bpy.app.tempdir or os.path.join(os.getcwd(), "tendril_cache"), "tendril_cache", f"{safe}.pc2")
    return path, path


def _same_positions(obj, rest):
    me = obj.data
    if len(me.vertices) != len(rest):
        return False
    if len(rest) == 0:
        return True
    import numpy as np
    co = np.empty(len(rest) * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    return float(np.abs(co.reshape(-1, 3) - rest).max()) < 1e-4


class TENDRIL_OT_clear_wind(_TendrilOperator, bpy.types.Operator):
    """Remove the wind animation (shape keys and their action) from the selected Tendril plants"""
    bl_idname = "tendril.clear_wind"
    bl_label = "Remove Wind Animation"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):  # needs no module
        objs = _selected_plants(context)
        if not objs:
            self.report({'ERROR'}, "Select plants grown by Tendril")
            return {'CANCELLED'}
        for o in objs:
            wind.clear(o)
        return {'FINISHED'}


# --- Attractors from grease pencil ------------------------------------------------------------

def _grease_pencil_strokes(obj, frame):
    """World-space point lists of the visible strokes of a grease pencil object at `frame`."""
    mw = obj.matrix_world
    out = []
    if obj.type == 'GPENCIL':  # Blender < 4.3
        for layer in obj.data.layers:
            if layer.hide:
                continue
            frames = [f for f in layer.frames if f.frame_number <= frame]
            gp_frame = max(frames, key=lambda f: f.frame_number) if frames else layer.active_frame
            if gp_frame is None:
                continue
            for stroke in gp_frame.strokes:
                out.append([mw @ p.co for p in stroke.points])
    elif obj.type == 'GREASEPENCIL':  # Blender 4.3+
        for layer in obj.data.layers:
            if getattr(layer, "hide", False):
                continue
            gp_frame = layer.current_frame()
            if gp_frame is None or gp_frame.drawing is None:
                continue
            for stroke in gp_frame.drawing.strokes:
                out.append([mw @ Vector(p.position) for p in stroke.points])
    return out


def _thin(points, spacing):
    if spacing <= 0 or len(points) < 2:
        return points
    kept = [points[0]]
    for p in points[1:]:
        if (p - kept[-1]).length >= spacing:
            kept.append(p)
    if kept[-1] is not points[-1] and (points[-1] - kept[-1]).length > 1e-9:
        kept.append(points[-1])
    return kept


class TENDRIL_OT_paint_attractors(_TendrilOperator, bpy.types.Operator):
    """Store the active grease pencil object's strokes as attractors (or repulsors) for the next
    grow"""
    bl_idname = "tendril.paint_attractors"
    bl_label = "Paint Attractors"
    bl_options = {'REGISTER', 'UNDO'}

    kind: EnumProperty(name="Kind", items=[("attract", "Attract", "Pull growth toward the strokes"),
                                          ("repel", "Repel", "Push growth away from the strokes")],
                       default="attract")
    radius: FloatProperty(name="Radius", default=0.3, min=0.0001, max=1000.0, unit='LENGTH',
                          description="Reach of each stroke point")
    strength: FloatProperty(name="Strength", default=1.0, min=0.0, max=1000000.0)
    spacing: FloatProperty(name="Spacing", default=0.05, min=0.0, soft_max=1.0, unit='LENGTH',
                           description="Keep stroke points at least this far apart (0 = all points)")
    replace: BoolProperty(name="Replace", default=True,
                          description="Replace the stored strokes (else add to them)")

    def execute(self, context):  # needs no module
        try:
            return self._run(context)
        except UserError as e:
            self.report({'ERROR'}, str(e))
        except Exception as e:
            traceback.print_exc()
            self.report({'ERROR'}, f"Tendril add-on: unexpected {type(e).__name__}: {e}")
        return {'CANCELLED'}

    def _run(self, context):
        gp_types = {'GPENCIL', 'GREASEPENCIL'}
        obj = context.view_layer.objects.active
        if obj is None or obj.type not in gp_types:
            obj = next((o for o in context.selected_objects if o.type in gp_types), None)
        if obj is None:
            raise UserError("Make a grease pencil object active: its strokes become the attractors")
        strokes = []
        n_points = 0
        for pts in _grease_pencil_strokes(obj, context.scene.frame_current):
            pts = _thin(pts, self.spacing)
            if not pts:
                continue
            strokes.append({"kind": self.kind, "radius": round(self.radius, 6), "strength": round(self.strength, 6),
                            "points": [convert.rounded(convert.vec_to_tendril(p)) for p in pts]})
            n_points += len(pts)
        if not strokes:
            raise UserError(f"{obj.name} has no strokes at frame {context.scene.frame_current}")
        settings = context.scene.tendril
        old = [] if self.replace else scene_doc.stored_strokes(context.scene)
        settings.strokes_json = json.dumps(old + strokes, separators=(",", ":"))
        self.report({'INFO'}, f"Tendril: {len(strokes)} {self.kind} stroke(s), {n_points} points from "
                              f"{obj.name} for the next grow")
        return {'FINISHED'}


class TENDRIL_OT_clear_attractors(bpy.types.Operator):
    """Forget the stored attractor strokes"""
    bl_idname = "tendril.clear_attractors"
    bl_label = "Clear Attractors"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):
        context.scene.tendril.strokes_json = ""
        return {'FINISHED'}


# --- Misc ---------------------------------------------------------------------------------------

class TENDRIL_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the scene document that grew the active plant (for the tendril command line)"""
    bl_idname = "tendril.export_scene"
    bl_label = "Export Tendril Scene"
    bl_options = {'REGISTER', 'UNDO'}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={'HIDDEN'})

    @classmethod
    def poll(cls, context):
        return build.is_tendril_object(context.view_layer.objects.active)

    def execute(self, context):
        obj = context.view_layer.objects.active
        try:
            doc = json.loads(obj[build.PROP_SCENE])
            with open(self.filepath, "w", encoding="utf-8") as f:
                json.dump(doc, f, indent=1)
                f.write("\n")
        except (OSError, ValueError) as e:
            self.report({'ERROR'}, f"Cannot write {self.filepath}: {e}")
            return {'CANCELLED'}
        self.report({'INFO'}, f"Wrote {self.filepath}")
        return {'FINISHED'}


class TENDRIL_OT_reload_module(bpy.types.Operator):
    """Look for Tendril's Python module again (after setting the module path)"""
    bl_idname = "tendril.reload_module"
    bl_label = "Reload Tendril Module"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):
        backend.reset()
        if backend.load() is None:
            self.report({'ERROR'}, backend.status())
            return {'CANCELLED'}
        self.report({'INFO'}, f"Tendril {backend.version()}")
        return {'FINISHED'}


classes = (
    TENDRIL_OT_grow_ivy,
    TENDRIL_OT_add_lsystem_plant,
    TENDRIL_OT_add_graph_plant,
    TENDRIL_OT_wind_animation,
    TENDRIL_OT_clear_wind,
    TENDRIL_OT_paint_attractors,
    TENDRIL_OT_clear_attractors,
    TENDRIL_OT_export_scene,
    TENDRIL_OT_reload_module,
)

"""Headless test of the Tendril Blender add-on (blender/tendril_blender, docs/blender.md).

    blender -b --factory-startup --python tests/blender/test_addon.py -- BLENDER_DIR MODULE_DIR

BLENDER_DIR holds the add-on package (tendril_blender/), MODULE_DIR the `tendril` Python
package (e.g. build/ci/python).  Both default to this checkout's.  Prints one line per check and
exits non-zero on any failure.
"""

import json
import os
import sys
import tempfile
import time
import traceback

import addon_utils
import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
ADDON_DIR = os.path.abspath(ARGS[0]) if len(ARGS) > 0 else os.path.join(REPO, "blender")
MODULE_DIR = os.path.abspath(ARGS[1]) if len(ARGS) > 1 else os.path.join(REPO, "build", "ci", "python")

T0 = time.perf_counter()
FAILURES = []


class Abort(Exception):
    pass


def check(name, ok, detail=""):
    line = f"{'ok  ' if ok else 'FAIL'} {name}" + (f" ({detail})" if detail else "")
    print(line, flush=True)
    if not ok:
        FAILURES.append(line)
    return ok


def require(name, ok, detail=""):
    if not check(name, ok, detail):
        raise Abort(name)


def plants():
    """The add-on's objects, by name (Python references do not survive an undo)."""
    return sorted((o for o in bpy.data.objects if "tendril_scene" in o), key=lambda o: o.name)


def positions(obj):
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float64)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def world_positions(obj):
    mw = np.array(obj.matrix_world)
    return positions(obj) @ mw[:3, :3].T + mw[:3, 3]


def evaluated_positions(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    ob = obj.evaluated_get(dg)
    me = ob.to_mesh()
    co = np.empty(len(me.vertices) * 3, dtype=np.float64)
    me.vertices.foreach_get("co", co)
    ob.to_mesh_clear()
    return co.reshape(-1, 3)


def expect_error(name, op, **kwargs):
    """The operator must report an error (bpy.ops raises RuntimeError for an ERROR report)
    and create nothing."""
    before = {o.name for o in bpy.data.objects}
    try:
        result = op('EXEC_DEFAULT', **kwargs)
    except RuntimeError as e:
        msg = str(e).strip().splitlines()[0]
        after = {o.name for o in bpy.data.objects}
        return check(name, after == before, f"reported: {msg[:150]}" + ("" if after == before else f"; but created {after - before}"))
    return check(name, False, f"no error, returned {result}")


def select(objs):
    bpy.ops.object.select_all(action='DESELECT')
    for o in objs:
        o.select_set(True)
    if objs:
        bpy.context.view_layer.objects.active = objs[0]


class FakeLayout:
    """Stands in for a UILayout (there are no UI regions in background mode): accepts any call
    and records the labels and operators drawn, so the panels' and redo panels' draw code runs."""

    def __init__(self, log):
        self.__dict__["log"] = log

    def __getattr__(self, name):
        def call(*args, **kwargs):
            if name in ("label", "operator", "prop"):
                self.log.append((name, kwargs.get("text", args[1] if name == "prop" and len(args) > 1 else
                                                  args[0] if args else "")))
            return FakeLayout(self.log)
        return call

    def __setattr__(self, name, value):
        pass


def draw_ui(name):
    """Draws the sidebar panels and every operator's redo panel into FakeLayouts."""
    import types
    from tendril_blender import operators, ui
    log = []
    for panel in (ui.VIEW3D_PT_tendril, ui.VIEW3D_PT_tendril_attractors, ui.VIEW3D_PT_tendril_wind,
                  ui.VIEW3D_PT_tendril_plant):
        if hasattr(panel, "poll") and not panel.poll(bpy.context):
            continue
        panel.draw(types.SimpleNamespace(layout=FakeLayout(log)), bpy.context)
    for cls in operators.classes:
        if "draw" not in cls.__dict__:
            continue
        op_module, op_name = cls.bl_idname.split(".")
        own = [p for p in getattr(getattr(bpy.ops, op_module), op_name).get_rna_type().properties
               if p.identifier != "rna_type"]
        props = {}
        for p in own:
            if p.type != 'ENUM':
                props[p.identifier] = p.default_array[:] if getattr(p, "is_array", False) else p.default
            elif p.enum_items:   # static items (reading a dynamic enum's default only warns)
                props[p.identifier] = p.default
            else:
                model = {"species": "climb", "grammar": "lsystem", "graph": "graph"}[p.identifier]
                props[p.identifier] = operators.preset_items(model, "x")[0][0]
        fake = types.SimpleNamespace(layout=FakeLayout(log), **props)
        for method in ("draw_environment",):
            if hasattr(cls, method):
                setattr(fake, method, types.MethodType(getattr(cls, method), fake))
        cls.draw(fake, bpy.context)
    return check(name, len(log) > 20, f"{len(log)} items drawn")


def render_check(ivy):
    """The grown ivy renders: a small Eevee picture from in front of the wall, where the ivy's
    leaves are green against the grey wall (render_ivy.py makes the README's picture the same way)."""
    scene = bpy.context.scene
    cam_data = bpy.data.cameras.new("TestCamera")
    cam = bpy.data.objects.new("TestCamera", cam_data)
    scene.collection.objects.link(cam)
    centre = ivy.matrix_world @ Vector(np.mean(positions(ivy), axis=0).tolist())
    cam.location = centre + Vector((0.0, -3.0, 0.4))
    cam.rotation_euler = (centre - cam.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = cam
    sun = bpy.data.objects.new("TestSun", bpy.data.lights.new("TestSun", "SUN"))
    scene.collection.objects.link(sun)
    sun.rotation_euler = (0.6, 0.2, 0.3)
    scene.render.engine = "BLENDER_EEVEE"
    scene.eevee.taa_render_samples = 4
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 160, 120, 100
    out = os.path.join(tempfile.mkdtemp(prefix="tendril-render-"), "ivy.png")
    scene.render.filepath = out
    t = time.time()
    try:
        bpy.ops.render.render(write_still=True)
    except RuntimeError as e:
        check("the grown ivy renders (Eevee, 160 x 120)", False, str(e))
        return
    img = bpy.data.images.load(out)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(-1, 4)
    green = int(np.sum((px[:, 1] > px[:, 0] * 1.15) & (px[:, 1] > px[:, 2] * 1.15) & (px[:, 1] > 0.05)))
    check("the grown ivy renders (Eevee, 160 x 120)", green > 300,
          f"{green} green pixels of {len(px)}, {time.time() - t:.1f} s")
    bpy.data.images.remove(img)
    for o in (cam, sun):
        bpy.data.objects.remove(o)


def run():
    # --- enable --------------------------------------------------------------------------------
    if ADDON_DIR not in sys.path:
        sys.path.insert(0, ADDON_DIR)
    mod = addon_utils.enable("tendril_blender", default_set=True, persistent=True)
    require("add-on enabled", mod is not None and hasattr(bpy.ops.tendril, "grow_ivy"), ADDON_DIR)
    from tendril_blender import backend
    prefs = bpy.context.preferences.addons["tendril_blender"].preferences
    importable = False
    try:
        import tendril  # noqa: F401  (installed into Blender's Python already?)
        importable = hasattr(tendril, "Session")
    except ImportError:
        pass
    if not importable and not os.environ.get(backend.ENV_VAR):
        # Not findable yet: the add-on must say so, and its operators report it.
        backend.reset()
        check("without the module: a clear status", backend.load() is None and "not found" in backend.status(),
              backend.status()[:80] + "...")
        expect_error("without the module: grow_ivy reports it", bpy.ops.tendril.grow_ivy, steps=1)
    prefs.module_path = MODULE_DIR
    backend.reset()
    tendril = backend.load()
    require("tendril module found through the preferences' Module path", tendril is not None,
            f"version {backend.version()}" if tendril else backend.status() + " | " + " | ".join(backend.attempts()))
    print(f"     module: {tendril.__file__}")
    draw_ui("panels and redo panels draw")
    check("presets", bool(backend.presets("climb")) and bool(backend.presets("lsystem")),
          ", ".join(f"{m}: {len(backend.presets(m))}" for m in ("climb", "particles", "lsystem", "graph")))

    # --- scene: a wall (a scaled cube) on a ground plane, the cursor at the wall's foot ---------
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 0.0, 0.0))
    ground = bpy.context.active_object
    ground.name = "Ground"
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 1.25))
    wall = bpy.context.active_object
    wall.name = "Wall"
    wall.scale = (3.0, 0.25, 2.5)          # front face at y = -0.125, not applied: the add-on evaluates
    bevel = wall.modifiers.new("Bevel", 'BEVEL')   # modifiers are applied to supports
    bevel.width = 0.01
    select([wall, ground])
    bpy.context.scene.cursor.location = (0.3, -0.16, 0.0)   # 3.5 cm from the wall: ivy adheres within 8 cm
    bpy.ops.ed.undo_push(message="setup")   # background mode: undo starts with an explicit push

    # --- grow ivy ---------------------------------------------------------------------------------
    t = time.perf_counter()
    res = bpy.ops.tendril.grow_ivy('EXEC_DEFAULT', True, steps=60, seed=3, radial_segments=6, subdivisions=2)
    grow_s = time.perf_counter() - t
    grown = plants()
    require("grow_ivy finished", res == {'FINISHED'} and len(grown) >= 1, f"{res}, {len(grown)} object(s), {grow_s:.1f} s")
    ivy = grown[0]
    me = ivy.data
    check("ivy mesh has vertices and faces", len(me.vertices) > 0 and len(me.polygons) > 0,
          f"{len(me.vertices)} vertices, {len(me.polygons)} faces")
    mats = [m for m in me.materials if m is not None]
    kinds = {m.get("tendril_kind") for m in mats}
    check("bark and leaf materials", len(mats) >= 2 and "bark" in kinds and "leaf" in kinds,
          ", ".join(f"{m.name} [{m.get('tendril_kind')}]" for m in mats))
    leaf = [m for m in mats if m.get("tendril_kind") == "leaf"]
    check("leaf material clips alpha at 0.5",
          bool(leaf) and all(m.blend_method == 'CLIP' and abs(m.alpha_threshold - 0.5) < 1e-6 for m in leaf),
          ", ".join(f"{m.name}: {m.blend_method} {m.alpha_threshold:.2f}" for m in leaf))
    check("materials use Principled BSDF",
          all(any(n.bl_idname == "ShaderNodeBsdfPrincipled" for n in m.node_tree.nodes) for m in mats))
    packed = [i for i in bpy.data.images if i.packed_file is not None]
    check("packed image texture", bool(packed) and all(i.size[0] > 0 for i in packed),
          ", ".join(f"{i.name} {i.size[0]}x{i.size[1]}" for i in packed))
    used_images = {n.image.name for m in mats for n in m.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage" and n.image}
    check("materials use the packed images", bool(used_images), ", ".join(sorted(used_images)))
    check("uvs and custom normals", len(me.uv_layers) == 1 and me.has_custom_normals)
    doc = json.loads(ivy["tendril_scene"])
    obstacles = doc["environment"]["obstacles"]
    check("stored scene document", doc.get("tendril") == 1 and len(doc["plants"]) == 1 and len(obstacles) == 2,
          f"{len(ivy['tendril_scene'])} chars, obstacles {[o['name'] for o in obstacles]}")
    # Y-up conversion: the wall's mesh obstacle spans Tendril y (Blender z) 0..2.5, z (-Blender y) +-0.125
    wv = np.array([o for o in obstacles if o["name"] == "Wall"][0]["vertices"]).reshape(-1, 3)
    check("supports sent in Tendril coordinates (Y-up, modifiers applied)",
          abs(wv[:, 1].min()) < 1e-4 and abs(wv[:, 1].max() - 2.5) < 1e-4 and abs(wv[:, 2].max() - 0.125) < 1e-4
          and abs(wv[:, 0].max() - 1.5) < 1e-4 and len(wv) > 8,
          f"{len(wv)} vertices, y {wv[:, 1].min():.3f}..{wv[:, 1].max():.3f}, z {wv[:, 2].min():.3f}..{wv[:, 2].max():.3f}")
    p = doc["plants"][0]
    check("seed snapped to the ground under the cursor, growing up (Tendril +Y)",
          abs(p["position"][0] - 0.3) < 1e-3 and abs(p["position"][2] - 0.16) < 1e-3 and 0 <= p["position"][1] < 0.01
          and p["direction"][1] > 0.99, f"position {p['position']}, direction {p['direction']}")
    wp = world_positions(ivy)
    inside = np.all((np.abs(wp[:, 0]) < 1.49, np.abs(wp[:, 1]) < 0.12, wp[:, 2] > 0.01, wp[:, 2] < 2.49), axis=0)
    check("ivy climbs the wall in front of it (Z-up result)",
          wp[:, 2].max() > 0.4 and wp[:, 1].min() < -0.125 and inside.mean() < 0.01,
          f"top z {wp[:, 2].max():.2f} m, min y {wp[:, 1].min():.3f}, {inside.sum()} of {len(wp)} vertices inside the wall")
    check("object origin at the seed", (ivy.location - bpy.context.scene.cursor.location).length < 0.02,
          f"{tuple(round(c, 3) for c in ivy.location)}")
    first = {o.name: positions(o) for o in grown}
    draw_ui("panels draw with a plant active")
    render_check(ivy)

    # --- undo, redo, grow again -----------------------------------------------------------------
    bpy.ops.ed.undo()
    check("undo removes the grown objects", not plants(), f"left: {[o.name for o in plants()]}")
    bpy.ops.ed.redo()
    check("redo brings them back", sorted(first) == [o.name for o in plants()])
    bpy.ops.ed.undo()
    # the redo panel: Blender undoes and runs execute again with the new values
    select([bpy.data.objects["Wall"], bpy.data.objects["Ground"]])
    bpy.ops.tendril.grow_ivy('EXEC_DEFAULT', True, steps=30, seed=3, radial_segments=6, subdivisions=2)
    fewer = sum(len(o.data.vertices) for o in plants())
    check("grow again with fewer steps", 0 < fewer < sum(len(v) for v in first.values()),
          f"{fewer} vertices vs {sum(len(v) for v in first.values())}")
    bpy.ops.ed.undo()
    check("undo again", not plants())
    select([bpy.data.objects["Wall"], bpy.data.objects["Ground"]])
    bpy.ops.tendril.grow_ivy('EXEC_DEFAULT', True, steps=60, seed=3, radial_segments=6, subdivisions=2)
    again = {o.name: positions(o) for o in plants()}
    check("same parameters give the same plant (deterministic redo)",
          sorted(again) == sorted(first) and all(np.array_equal(again[k], first[k]) for k in first))

    # --- wind animation ----------------------------------------------------------------------------
    ivy_objs = plants()
    select(ivy_objs)
    t = time.perf_counter()
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    res = bpy.ops.tendril.wind_animation('EXEC_DEFAULT', True, mode='GUSTY', speed=2.0, seconds=0.5, fps=0,
                                         frame_start=1, method='SHAPE_KEYS')
    wind_s = time.perf_counter() - t
    ivy = plants()[0]
    keys = ivy.data.shape_keys
    n_keys = len(keys.key_blocks) if keys else 0
    check("wind_animation finished with shape keys", res == {'FINISHED'} and n_keys == 13,
          f"{res}, {n_keys} keys (basis + 12 frames), {wind_s:.1f} s")
    action = keys.animation_data.action if keys and keys.animation_data else None
    check("shape keys keyframed", action is not None and len(action.fcurves) == 12,
          f"{len(action.fcurves) if action else 0} F-curves")
    check("frame range set to the loop", (scene.frame_start, scene.frame_end) == (1, 12),
          f"{scene.frame_start}..{scene.frame_end}")
    scene.frame_set(1)
    a = evaluated_positions(ivy)
    scene.frame_set(4)
    b = evaluated_positions(ivy)
    scene.frame_set(13)
    c = evaluated_positions(ivy)
    scene.frame_set(1)
    check("two frames' evaluated positions differ", a.shape == b.shape and float(np.abs(a - b).max()) > 1e-5,
          f"max difference {float(np.abs(a - b).max()):.4f} m")
    check("the clip loops (frame 13 == frame 1)", float(np.abs(a - c).max()) < 1e-5,
          f"max difference {float(np.abs(a - c).max()):.2e}")
    check("rest shape kept (gusts below the species' wind_min)", np.array_equal(positions(ivy), again[ivy.name]))
    # The same clip as a PC2 point cache read by a Mesh Cache modifier.
    res = bpy.ops.tendril.wind_animation('EXEC_DEFAULT', True, mode='GUSTY', speed=2.0, seconds=0.5, fps=0,
                                         frame_start=1, method='MESH_CACHE')
    ivy = plants()[0]
    mod = ivy.modifiers.get("Tendril wind")
    check("wind as a Mesh Cache replaces the shape keys", res == {'FINISHED'} and ivy.data.shape_keys is None
          and mod is not None and os.path.isfile(bpy.path.abspath(mod.filepath)),
          f"{mod.filepath if mod else None}")
    posed = []
    for f in (1, 4, 13):
        scene.frame_set(f)
        posed.append(evaluated_positions(ivy))
    scene.frame_set(1)
    check("the Mesh Cache plays the same clip, looping",
          float(np.abs(posed[0] - a).max()) < 1e-5 and float(np.abs(posed[1] - b).max()) < 1e-5
          and float(np.abs(posed[2] - a).max()) < 1e-5,
          f"frame 4 differs from the shape keys' by {float(np.abs(posed[1] - b).max()):.1e} m")
    # A wind above wind_min changes growth (Growth-Flow): the rest shape is rebuilt, keys match it.
    res = bpy.ops.tendril.wind_animation('EXEC_DEFAULT', True, mode='CONSTANT', speed=14.0, seconds=0.25, fps=0,
                                         frame_start=1, method='SHAPE_KEYS')
    ivy = plants()[0]
    rest = positions(ivy)
    keys = ivy.data.shape_keys
    check("a strong wind regrows the rest shape and re-keys it",
          res == {'FINISHED'} and not (rest.shape == again[ivy.name].shape and np.array_equal(rest, again[ivy.name]))
          and keys is not None and len(keys.key_blocks) == 7 and len(keys.key_blocks[1].data) == len(rest),
          f"{len(again[ivy.name])} -> {len(rest)} vertices, {len(keys.key_blocks) if keys else 0} keys")

    # --- attractors from grease pencil ------------------------------------------------------------
    gpd = bpy.data.grease_pencils.new("Strokes")
    layer = gpd.layers.new("Paint")
    frame = layer.frames.new(scene.frame_current)
    stroke = frame.strokes.new()
    stroke.points.add(5)
    for i, pt in enumerate(stroke.points):
        pt.co = (-1.0 + 0.25 * i, -0.14, 1.5 + 0.1 * i)
    gp = bpy.data.objects.new("Strokes", gpd)
    scene.collection.objects.link(gp)
    select([gp])
    res = bpy.ops.tendril.paint_attractors('EXEC_DEFAULT', True, radius=0.4, spacing=0.0)
    strokes = json.loads(scene.tendril.strokes_json or "[]")
    pts = strokes[0]["points"] if strokes else []
    check("paint_attractors stores grease pencil strokes in Tendril coordinates",
          res == {'FINISHED'} and len(strokes) == 1 and len(pts) == 5
          and np.allclose(pts[0], [-1.0, 1.5, 0.14]) and strokes[0]["kind"] == "attract",
          f"{len(strokes)} stroke(s), first point {pts[0] if pts else None}")
    select([bpy.data.objects["Wall"], bpy.data.objects["Ground"]])
    before = {o.name for o in plants()}
    res = bpy.ops.tendril.grow_ivy('EXEC_DEFAULT', True, steps=40, seed=5, radial_segments=6, subdivisions=2,
                                   placement='SCATTER', plant_count=3)
    new = [o for o in plants() if o.name not in before]
    sdoc = json.loads(new[0]["tendril_scene"]) if new else {}
    check("scattered seeds grow with the attractors", res == {'FINISHED'} and len(new) >= 1
          and len(sdoc.get("environment", {}).get("strokes", [])) == 1,
          f"{len(new)} plant(s): {[o.name for o in new]}")

    # --- L-system and graph plants ----------------------------------------------------------------
    select([bpy.data.objects["Wall"], bpy.data.objects["Ground"]])
    scene.cursor.location = (-0.8, -0.16, 0.0)
    grammars = backend.presets("lsystem")
    grammar = "japanese-ivy" if "japanese-ivy" in grammars else grammars[0]
    before = {o.name for o in plants()}
    t = time.perf_counter()
    res = bpy.ops.tendril.add_lsystem_plant('EXEC_DEFAULT', True, grammar=grammar, derivation_length=40,
                                            radial_segments=6, subdivisions=2)
    new = [o for o in plants() if o.name not in before]
    check(f"add_lsystem_plant ({grammar}, 40 steps)", res == {'FINISHED'} and len(new) == 1
          and len(new[0].data.polygons) > 0 and new[0]["tendril_model"] == "lsystem",
          f"{new[0].name if new else None}: {len(new[0].data.vertices) if new else 0} vertices, "
          f"{time.perf_counter() - t:.1f} s")
    ls_file = os.path.join(REPO, "examples", "grammars", "abop-1.24a.ls")
    if os.path.isfile(ls_file):
        bpy.ops.object.select_all(action='DESELECT')
        scene.cursor.location = (3.0, 2.0, 0.0)
        before = {o.name for o in plants()}
        res = bpy.ops.tendril.add_lsystem_plant('EXEC_DEFAULT', True, source='FILE', filepath=ls_file, scale=0.05,
                                                derivation_length=0)  # operators remember their last values
        new = [o for o in plants() if o.name not in before]
        check("add_lsystem_plant from a .ls file, no supports, scaled", res == {'FINISHED'} and len(new) == 1
              and abs(new[0].scale[0] - 0.05) < 1e-6, f"{new[0].name if new else None}")
    graphs = backend.presets("graph")
    bpy.ops.object.select_all(action='DESELECT')
    scene.cursor.location = (-3.0, 2.0, 0.0)
    before = {o.name for o in plants()}
    t = time.perf_counter()
    if graphs:
        from tendril_blender.operators import preset_label
        graph = next((g for g in graphs if preset_label(g) == "sunflower"), graphs[0])
        res = bpy.ops.tendril.add_graph_plant('EXEC_DEFAULT', True, graph=graph, use_ground=True)
        new = [o for o in plants() if o.name not in before]
        check(f"add_graph_plant ({preset_label(graph)}, on a ground)", res == {'FINISHED'} and len(new) >= 1
              and len(new[0].data.polygons) > 0,
              f"{new[0].name if new else None}: {len(new[0].data.vertices) if new else 0} vertices, "
              f"{time.perf_counter() - t:.1f} s")
    else:
        check("tendril.presets('graph') lists built-in graphs", False, "empty")
    graph_file = os.path.join(REPO, "examples", "graphs", "fig2.json")
    if os.path.isfile(graph_file):
        scene.cursor.location = (-3.0, 4.0, 0.0)
        before = {o.name for o in plants()}
        res = bpy.ops.tendril.add_graph_plant('EXEC_DEFAULT', True, source='FILE', filepath=graph_file,
                                              use_graph_seed=False, seed=4)
        new = [o for o in plants() if o.name not in before]
        check("add_graph_plant from a graph file", res == {'FINISHED'} and len(new) >= 1, f"{[o.name for o in new]}")

    # --- bad input: reported, nothing created, no crash -------------------------------------------
    bpy.ops.object.select_all(action='DESELECT')
    expect_error("grow_ivy with nothing selected and no ground", bpy.ops.tendril.grow_ivy, steps=10, use_ground=False)
    select([bpy.data.objects["Wall"]])
    scene.cursor.location = (0.0, 0.0, 1.0)   # inside the wall
    expect_error("grow_ivy with the seed inside the wall (no snapping)", bpy.ops.tendril.grow_ivy, steps=10,
                 snap_to_surface=False)
    expect_error("grow_ivy with a missing species file", bpy.ops.tendril.grow_ivy, steps=10,
                 species_file="/nonexistent/species.json")
    expect_error("add_lsystem_plant with a missing grammar file", bpy.ops.tendril.add_lsystem_plant,
                 source='FILE', filepath="/nonexistent/grammar.ls")
    expect_error("add_graph_plant with a missing graph file", bpy.ops.tendril.add_graph_plant,
                 source='FILE', filepath="/nonexistent/graph.json")
    if graphs:
        expect_error("add_graph_plant with bad overrides", bpy.ops.tendril.add_graph_plant, graph=graphs[0],
                     overrides="{not json")
    bad = os.path.join(bpy.app.tempdir or "/tmp", "tendril-bad-grammar.ls")
    with open(bad, "w") as f:
        f.write("axiom: X\nX -> F[+X\n")
    expect_error("add_lsystem_plant with a broken grammar", bpy.ops.tendril.add_lsystem_plant, source='FILE',
                 filepath=bad)
    bpy.ops.object.select_all(action='DESELECT')
    expect_error("wind_animation with no plant selected", bpy.ops.tendril.wind_animation, seconds=1.0, fps=4)
    expect_error("paint_attractors with no grease pencil", bpy.ops.tendril.paint_attractors)


def main():
    try:
        run()
    except Abort:
        pass
    except Exception:
        traceback.print_exc()
        FAILURES.append("exception")
        print("FAIL unexpected exception (above)")
    elapsed = time.perf_counter() - T0
    if FAILURES:
        print(f"FAILED: {len(FAILURES)} check(s) ({elapsed:.1f} s)", flush=True)
        sys.exit(1)
    print(f"PASSED ({elapsed:.1f} s)", flush=True)
    sys.exit(0)


main()

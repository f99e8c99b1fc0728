"""Render ivy grown by the Tendril add-on, headless.

    blender -b --factory-startup --python examples/blender/render_ivy.py -- OUT.png \
        [--module-dir build/ci/python] [--addon-dir blender] [--engine EEVEE|CYCLES] \
        [--samples N] [--width W] [--height H] [--steps 220] [--blend OUT.blend]

Builds a brick wall with a window (a Boolean modifier: supports are evaluated with their
modifiers) on a ground plane, grows two ivies at the wall's foot with the add-on's operator
(tendril.grow_ivy), then lights it with a sun and a sky-coloured world and renders.  Eevee needs
an OpenGL context; if it cannot get one, run under `xvfb-run -a` or use `--engine CYCLES`.
See docs/blender.md.
"""

import argparse
import math
import os
import sys
import time

import addon_utils
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="render_ivy.py")
    p.add_argument("output", help="PNG to write")
    p.add_argument("--module-dir", default=os.environ.get("TENDRIL_PYTHON_PATH") or os.path.join(REPO, "build", "ci", "python"),
                   help="directory holding the 'tendril' Python package")
    p.add_argument("--addon-dir", default=os.path.join(REPO, "blender"),
                   help="directory holding the add-on package tendril_blender/")
    p.add_argument("--engine", choices=["EEVEE", "CYCLES"], default="EEVEE")
    p.add_argument("--samples", type=int, default=0, help="render samples (default: Eevee 32, Cycles 16)")
    p.add_argument("--width", type=int, default=0, help="default: Eevee 1280, Cycles 640")
    p.add_argument("--height", type=int, default=0, help="default: Eevee 720, Cycles 480")
    p.add_argument("--steps", type=int, default=220, help="growth steps of each ivy")
    p.add_argument("--blend", default="", help="also save the scene as this .blend")
    return p.parse_args(argv)


def material(name, colour, roughness=0.8):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    mat.diffuse_color = (*colour, 1.0)
    return mat, bsdf


def brick_material():
    """Bricks in world metres on the wall's XZ face (procedural: no files needed)."""
    mat, bsdf = material("Brick", (0.45, 0.2, 0.13), 0.9)
    nt = mat.node_tree
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    nt.links.new(geo.outputs["Position"], sep.inputs[0])
    nt.links.new(sep.outputs["X"], comb.inputs["X"])
    nt.links.new(sep.outputs["Z"], comb.inputs["Y"])
    nt.links.new(sep.outputs["Y"], comb.inputs["Z"])
    brick = nt.nodes.new("ShaderNodeTexBrick")
    brick.offset = 0.5
    brick.inputs["Scale"].default_value = 1.0
    brick.inputs["Brick Width"].default_value = 0.24
    brick.inputs["Row Height"].default_value = 0.075
    brick.inputs["Mortar Size"].default_value = 0.004
    brick.inputs["Color1"].default_value = (0.28, 0.085, 0.045, 1.0)
    brick.inputs["Color2"].default_value = (0.38, 0.13, 0.07, 1.0)
    brick.inputs["Mortar"].default_value = (0.45, 0.43, 0.4, 1.0)
    nt.links.new(comb.outputs[0], brick.inputs["Vector"])
    nt.links.new(brick.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


def build_scene():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    scene = bpy.context.scene

    bpy.ops.mesh.primitive_plane_add(size=30.0, location=(0.0, 0.0, 0.0))
    ground = bpy.context.active_object
    ground.name = "Ground"
    ground.data.materials.append(material("Ground", (0.1, 0.13, 0.06), 1.0)[0])

    # The wall: a cube scaled to 4 x 0.3 x 3 m with a window cut by a Boolean modifier.
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 1.5))
    wall = bpy.context.active_object
    wall.name = "Wall"
    wall.scale = (4.0, 0.3, 3.0)
    wall.data.materials.append(brick_material())
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.75, 0.0, 1.85))
    window = bpy.context.active_object
    window.name = "Window cutter"
    window.scale = (1.1, 1.0, 1.0)
    window.hide_render = True
    window.display_type = 'WIRE'
    window.hide_set(True)
    cut = wall.modifiers.new("Window", 'BOOLEAN')
    cut.operation = 'DIFFERENCE'
    cut.object = window

    bpy.ops.object.select_all(action='DESELECT')
    wall.select_set(True)
    ground.select_set(True)
    bpy.context.view_layer.objects.active = wall
    return scene, wall, ground


def light_and_camera(scene):
    sun_data = bpy.data.lights.new("Sun", 'SUN')
    sun_data.energy = 3.0
    sun_data.angle = math.radians(2.0)
    sun_data.use_contact_shadow = True   # Eevee: leaves shade the bricks right under them
    sun_data.contact_shadow_distance = 0.1
    sun = bpy.data.objects.new("Sun", sun_data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.radians(48.0), 0.0, math.radians(-40.0))

    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.3, 0.5, 0.95, 1.0)
    bg.inputs["Strength"].default_value = 0.65

    cam_data = bpy.data.cameras.new("Camera")
    cam_data.lens = 38.0
    cam = bpy.data.objects.new("Camera", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (-3.2, -6.4, 1.9)
    target = bpy.data.objects.new("Camera target", None)
    scene.collection.objects.link(target)
    target.location = (0.15, 0.0, 1.4)
    track = cam.constraints.new('TRACK_TO')
    track.target = target
    track.track_axis = 'TRACK_NEGATIVE_Z'
    track.up_axis = 'UP_Y'
    scene.camera = cam


def render_settings(scene, args):
    eevee = args.engine == 'EEVEE'
    scene.render.resolution_x = args.width or (1280 if eevee else 640)
    scene.render.resolution_y = args.height or (720 if eevee else 480)
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = 'PNG'
    scene.render.filepath = os.path.abspath(args.output)
    scene.view_settings.view_transform = 'Filmic'
    scene.view_settings.look = 'Medium Contrast'
    if args.engine == 'EEVEE':
        scene.render.engine = 'BLENDER_EEVEE'
        ee = scene.eevee
        ee.taa_render_samples = args.samples or 32
        ee.use_gtao = True
        ee.gtao_distance = 0.4
        ee.use_soft_shadows = True
        ee.shadow_cascade_size = '4096'
        ee.shadow_cube_size = '2048'
        for light in bpy.data.lights:
            if light.type == 'SUN':
                light.shadow_cascade_max_distance = 20.0
                light.shadow_cascade_count = 4
    else:
        scene.render.engine = 'CYCLES'
        scene.cycles.device = 'CPU'
        scene.cycles.samples = args.samples or 16
        # Debian's Blender is built without OpenImageDenoise
        scene.cycles.use_denoising = bool(getattr(bpy.app.build_options, "openimagedenoise", False))


def main():
    args = parse_args()
    if args.addon_dir not in sys.path:
        sys.path.insert(0, args.addon_dir)
    if addon_utils.enable("tendril_blender", default_set=True) is None:
        raise SystemExit(f"cannot enable the add-on from {args.addon_dir}")
    prefs = bpy.context.preferences.addons["tendril_blender"].preferences
    prefs.module_path = args.module_dir
    from tendril_blender import backend
    backend.reset()
    if backend.load() is None:
        raise SystemExit(backend.status() + "\n  " + "\n  ".join(backend.attempts()))
    print(f"Tendril {backend.version()} from {backend.load().__file__}")

    scene, wall, ground = build_scene()
    light_and_camera(scene)   # the sun also steers the ivy toward the light

    t = time.perf_counter()
    for i, (x, seed) in enumerate(((-1.2, 1), (0.9, 2))):
        scene.cursor.location = (x, -0.19, 0.0)   # 4 cm in front of the wall's face (y = -0.15)
        bpy.ops.object.select_all(action='DESELECT')
        wall.select_set(True)
        ground.select_set(True)
        res = bpy.ops.tendril.grow_ivy(steps=args.steps, seed=seed, radial_segments=8, subdivisions=3,
                                       placement='CURSOR', plant_count=1)
        if res != {'FINISHED'}:
            raise SystemExit(f"grow_ivy: {res}")
    ivies = [o for o in bpy.data.objects if "tendril_scene" in o]
    print(f"grew {len(ivies)} ivies: {sum(len(o.data.vertices) for o in ivies)} vertices, "
          f"{sum(len(o.data.polygons) for o in ivies)} triangles in {time.perf_counter() - t:.1f} s")

    render_settings(scene, args)
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.blend))
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(f"rendered {scene.render.filepath} with {scene.render.engine} in {time.perf_counter() - t:.1f} s")


try:
    main()
except SystemExit:
    raise
except Exception:
    import traceback
    traceback.print_exc()
    sys.exit(1)

"""Render a plant's levels of detail side by side, headless, from the .glb `tendril` writes.

    tendril grow examples/scenes/default.json -o out --lods 4 --format glb
    xvfb-run -a blender -b --factory-startup --python examples/blender/render_lods.py -- \
        out/plant.glb OUT.png [--plant ivy-left] [--width 1600] [--height 600] [--samples 16]

Imports the file with Blender's glTF importer (Debian's Blender 3.4 needs numpy.bool, which
numpy 1.24 removed: set here), keeps one plant's <plant>_LOD0..N objects, lines them up left to
right with their triangle counts as labels, lights them with a sun and renders with Eevee. The
picture of docs/export.md.
"""

import argparse
import math
import os
import sys

import bpy
import numpy

numpy.bool = bool


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="render_lods.py")
    p.add_argument("glb")
    p.add_argument("output")
    p.add_argument("--plant", default="", help="the plant whose levels to show (default: the first)")
    p.add_argument("--width", type=int, default=1600)
    p.add_argument("--height", type=int, default=600)
    p.add_argument("--samples", type=int, default=16)
    return p.parse_args(argv)


def main():
    args = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(args.glb))
    levels = {}
    for o in bpy.data.objects:
        if o.type == "MESH" and "_LOD" in o.name:
            plant, level = o.name.rsplit("_LOD", 1)
            levels.setdefault(plant, {})[int(level)] = o
    if not levels:
        sys.exit(f"{args.glb}: no <plant>_LOD<n> objects (export with --lods N)")
    plant = args.plant or sorted(levels)[0]
    if plant not in levels:
        sys.exit(f"{args.glb}: no plant {plant!r} (there are {', '.join(sorted(levels))})")
    chain = [levels[plant][k] for k in sorted(levels[plant])]
    for o in list(bpy.data.objects):
        if o not in chain:
            bpy.data.objects.remove(o, do_unlink=True)

    scene = bpy.context.scene
    # Side by side along X, each level's bounds centred on its own slot.
    width = max(max(v.co.x for v in o.data.vertices) - min(v.co.x for v in o.data.vertices) for o in chain)
    height = max(max(v.co.z for v in o.data.vertices) for o in chain)
    for k, o in enumerate(chain):
        centre = 0.5 * (max(v.co.x for v in o.data.vertices) + min(v.co.x for v in o.data.vertices))
        o.parent = None
        o.location = (k * 1.15 * width - centre, 0.0, 0.0)
        tris = sum(len(p.vertices) - 2 for p in o.data.polygons)
        label = bpy.data.curves.new(f"label{k}", "FONT")
        label.body = f"LOD{k}: {tris:,} triangles"
        label.size = 0.07 * height
        label.align_x = "CENTER"
        text = bpy.data.objects.new(f"label{k}", label)
        text.location = (k * 1.15 * width, 0.0, -0.12 * height)
        text.rotation_euler = (math.radians(90), 0.0, 0.0)
        scene.collection.objects.link(text)
        ink = bpy.data.materials.new(f"ink{k}")
        ink.diffuse_color = (0.05, 0.05, 0.05, 1.0)
        label.materials.append(ink)

    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = 3.0
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (math.radians(50), math.radians(10), math.radians(30))
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("Sky")
    world.color = (0.75, 0.8, 0.85)
    scene.world = world
    span = (len(chain) - 1) * 1.15 * width
    cam_data = bpy.data.cameras.new("Camera")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = max(span + 1.3 * width, 1.4 * height * args.width / args.height)
    cam = bpy.data.objects.new("Camera", cam_data)
    cam.location = (0.5 * span, -10.0 * height, 0.42 * height)
    cam.rotation_euler = (math.radians(90), 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.engine = "BLENDER_EEVEE"
    scene.eevee.taa_render_samples = args.samples
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.filepath = os.path.abspath(args.output)
    scene.view_settings.view_transform = "Standard"
    bpy.ops.render.render(write_still=True)
    print(f"wrote {args.output}: {plant} LOD0..{len(chain) - 1}")


main()

"""Blender's own glTF importer (Debian's Blender 3.4, headless) reads what `tendril` exports:
levels of detail (nodes <plant>_LOD0..3, MSFT_lod), their materials and UVs, the leaf atlas, engine
wind data and the impostor level (<plant>_LOD4, output.impostor).

    blender -b --factory-startup --python tests/blender/test_gltf_import.py -- MODULE_DIR

MODULE_DIR holds the `tendril` Python package (default: build/ci/python). Prints one line per
check and exits non-zero on any failure. (Blender 3.4's importer leaves out application-specific
attributes such as _NODE_ID; docs/export.md says what each tool reads.)
"""

import os
import sys
import tempfile
import time
import traceback

import bpy
import numpy

# Debian 12's Blender 3.4 importer still uses numpy.bool, which Debian's numpy 1.24 removed.
numpy.bool = bool

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
MODULE_DIR = os.path.abspath(ARGS[0]) if ARGS else os.path.join(REPO, "build", "ci", "python")
sys.path.insert(0, MODULE_DIR)
import tendril  # noqa: E402

T0 = time.perf_counter()
FAILURES = []


def check(name, ok, detail=""):
    line = f"{'ok  ' if ok else 'FAIL'} {name}" + (f" ({detail})" if detail else "")
    print(line, flush=True)
    if not ok:
        FAILURES.append(line)


def triangles(obj):
    return sum(len(p.vertices) - 2 for p in obj.data.polygons)


def run():
    scene = tendril.Session.open(os.path.join(REPO, "examples", "scenes", "default.json")).scene
    scene["output"] = dict(scene.get("output", {}), lods=4, lod_ratio=0.5)
    session = tendril.Session(scene, base_dir=os.path.join(REPO, "examples", "scenes"))
    session.run(80)
    names = [session.plant(i).name for i in range(session.plant_count)]
    out = os.path.join(tempfile.mkdtemp(prefix="tendril-gltf-"), "plant.glb")
    session.export(out)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=out)
    check("the importer reads the file", result == {"FINISHED"}, str(result))
    meshes = {o.name: o for o in bpy.data.objects if o.type == "MESH"}
    for name in names:
        levels = [meshes.get(f"{name}_LOD{k}") for k in range(4)]
        check(f"{name}: objects {name}_LOD0..3", all(levels), ", ".join(sorted(meshes)))
        if not all(levels):
            continue
        counts = [triangles(o) for o in levels]
        check(f"{name}: triangles fall LOD0 > LOD1 > LOD2 > LOD3", all(a > b for a, b in zip(counts, counts[1:])),
              str(counts))
        check(f"{name}: LOD3 at most 1/8 of LOD0", counts[3] * 8 <= counts[0], str(counts))
        for k, obj in enumerate(levels):
            mats = [m.name for m in obj.data.materials if m]
            check(f"{name}_LOD{k}: bark and leaf materials", any("bark" in m for m in mats) and
                  any("leaf" in m or "leaves" in m for m in mats), str(mats))
            check(f"{name}_LOD{k}: a UV map", len(obj.data.uv_layers) >= 1)
            # Same place: every level's bounds within 10 % of LOD0's diagonal.
            lo0 = numpy.array([min(v.co[i] for v in levels[0].data.vertices) for i in range(3)])
            hi0 = numpy.array([max(v.co[i] for v in levels[0].data.vertices) for i in range(3)])
            lo = numpy.array([min(v.co[i] for v in obj.data.vertices) for i in range(3)])
            hi = numpy.array([max(v.co[i] for v in obj.data.vertices) for i in range(3)])
            diagonal = float(numpy.linalg.norm(hi0 - lo0))
            off = float(max(numpy.abs(lo - lo0).max(), numpy.abs(hi - hi0).max()))
            check(f"{name}_LOD{k}: bounds within 10 % of LOD0's", off <= 0.1 * diagonal, f"{off:.3f} of {diagonal:.3f} m")
    # Leaves are cut out by their texture's alpha (alphaMode MASK).
    leaf = [m for m in bpy.data.materials if "leaf" in m.name or "leaves" in m.name]
    check("leaf materials clip by alpha", leaf and all(m.blend_method == "CLIP" for m in leaf),
          str([(m.name, m.blend_method) for m in leaf]))

    # The leaf atlas (one leaf material per plant) and engine wind data (COLOR_0 becomes a colour
    # attribute; the _WIND_* and _NODE_ID attributes are not imported by Blender 3.4).
    scene["output"] = dict(scene["output"], leaf_atlas=True, wind_data=True)
    session = tendril.Session(scene, base_dir=os.path.join(REPO, "examples", "scenes"))
    session.run(80)
    out = os.path.join(os.path.dirname(out), "atlas.glb")
    session.export(out)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=out)
    check("the importer reads the atlas file", result == {"FINISHED"}, str(result))
    for name in names:
        obj = bpy.data.objects.get(f"{name}_LOD0")
        if not obj:
            check(f"{name}_LOD0 in the atlas file", False)
            continue
        mats = [m.name for m in obj.data.materials if m]
        leafs = [m for m in mats if "leaf" in m]
        check(f"{name}: one leaf material, the atlas", len(leafs) == 1 and "atlas" in leafs[0], str(mats))
        images = {n.image.name for m in obj.data.materials if m and m.node_tree
                  for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image and "leaf" in m.name}
        check(f"{name}: the atlas material has one image", len(images) == 1, str(images))
        colours = [a.name for a in obj.data.color_attributes] if hasattr(obj.data, "color_attributes") else []
        check(f"{name}: COLOR_0 (engine wind data) imported as a colour attribute", len(colours) >= 1, str(colours))
        if colours:
            data = obj.data.color_attributes[colours[0]].data
            values = numpy.zeros(len(data) * 4, dtype=numpy.float32)
            data.foreach_get("color", values)
            values = values.reshape(-1, 4)
            # The leaf flag (alpha) is 1 on leaf vertices and 0 on bark; the phase is in [0, 1).
            check(f"{name}: COLOR_0's leaf flag is 0 or 1 and both occur",
                  set(numpy.unique(numpy.round(values[:, 3], 3))) == {0.0, 1.0},
                  str(numpy.unique(numpy.round(values[:, 3], 3))[:5]))

    # The impostor (output.impostor): one more level, <plant>_LOD4, its quads in the alpha-clipped
    # material "impostor" with a base colour and a normal map.
    scene["output"] = dict(scene["output"], impostor=True)
    session = tendril.Session(scene, base_dir=os.path.join(REPO, "examples", "scenes"))
    session.run(80)
    out = os.path.join(os.path.dirname(out), "impostor.glb")
    session.export(out)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=out)
    check("the importer reads the impostor file", result == {"FINISHED"}, str(result))
    for name in names:
        obj = bpy.data.objects.get(f"{name}_LOD4")
        check(f"{name}: object {name}_LOD4, the impostor", obj is not None and obj.type == "MESH")
        if obj is None:
            continue
        check(f"{name}_LOD4: two triangles per quad", triangles(obj) * 2 == len(obj.data.vertices) and
              triangles(obj) > 0, f"{triangles(obj)} triangles, {len(obj.data.vertices)} vertices")
        mats = [m for m in obj.data.materials if m]
        check(f"{name}_LOD4: the impostor material clips by alpha",
              len(mats) == 1 and "impostor" in mats[0].name and mats[0].blend_method == "CLIP",
              str([(m.name, m.blend_method) for m in mats]))
        nodes = {n.type for n in mats[0].node_tree.nodes} if mats and mats[0].node_tree else set()
        check(f"{name}_LOD4: colour and normal textures", "TEX_IMAGE" in nodes and "NORMAL_MAP" in nodes, str(nodes))

    # Normal and roughness maps (output.maps): the bark's normal map feeds the shader's normal
    # through a Normal Map node, its roughness map the roughness; leaves get a normal map too.
    scene["output"] = dict(scene["output"], impostor=False, maps=True)
    session = tendril.Session(scene, base_dir=os.path.join(REPO, "examples", "scenes"))
    session.run(80)
    out = os.path.join(os.path.dirname(out), "maps.glb")
    session.export(out)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=out)
    check("the importer reads the file with maps", result == {"FINISHED"}, str(result))
    for kind in ("bark", "leaf"):
        mats = [m for m in bpy.data.materials if kind in m.name and m.node_tree]
        bsdf = [n for m in mats for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED"]
        normal = [b for b in bsdf if b.inputs["Normal"].is_linked and
                  b.inputs["Normal"].links[0].from_node.type == "NORMAL_MAP"]
        check(f"{kind}: the normal map drives the shader's normal", mats and len(normal) == len(bsdf) > 0,
              f"{len(normal)} of {len(bsdf)}")
        if kind == "bark":
            rough = [b for b in bsdf if b.inputs["Roughness"].is_linked]
            check("bark: the roughness map drives the roughness", len(rough) == len(bsdf) > 0,
                  f"{len(rough)} of {len(bsdf)}")

    # GPU instancing (output.instancing): EXT_mesh_gpu_instancing is required and Blender 3.4's
    # importer does not have it, so it refuses the file (docs/export.md) rather than showing one
    # copy of each shape.
    graph = os.path.join(REPO, "examples", "graphs", "fig2.json")
    out = os.path.join(os.path.dirname(out), "fig.glb")
    refused = ""
    try:
        import subprocess
        cli = os.path.join(MODULE_DIR, "..", "tendril")
        subprocess.run([cli, "model", graph, "-o", out, "--instancing", "-q"], check=True)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.import_scene.gltf(filepath=out)
    except RuntimeError as e:
        refused = str(e)
    check("an instanced file is refused, naming EXT_mesh_gpu_instancing", "EXT_mesh_gpu_instancing" in refused,
          refused.splitlines()[0] if refused else "imported")


def main():
    try:
        run()
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

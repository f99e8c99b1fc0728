"""Tendril scene documents (docs/scene-format.md) from the Blender scene: selected objects as
mesh obstacles, an optional ground plane, lights, painted strokes, and seed points on the
supports.  Everything sent to Tendril is converted from Blender's Z-up to Tendril's Y-up."""

import json
import math

import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

from . import convert
from .build import is_tendril_object

SUPPORT_TYPES = {'MESH', 'CURVE', 'SURFACE', 'META', 'FONT'}
SEED_OFFSET = 0.001   # seeds sit 1 mm off the surface they are snapped to, along its normal


class UserError(Exception):
    """Bad input from the user (reported as an error, never a traceback)."""


def support_objects(context):
    """Selected objects that can be supports: geometry, not plants grown by the add-on."""
    return [o for o in context.selected_objects if o.type in SUPPORT_TYPES and not is_tendril_object(o)]


def world_triangles(obj, depsgraph):
    """(vertices (n, 3) float64 in Blender world space, triangles (m, 3) int64) of the evaluated
    object (modifiers applied), triangulated; windings flipped under a mirroring transform so
    that normals keep pointing out."""
    ob_eval = obj.evaluated_get(depsgraph)
    me = ob_eval.to_mesh()
    try:
        if me is None:
            return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
        me.calc_loop_triangles()
        n = len(me.vertices)
        m = len(me.loop_triangles)
        co = np.empty(n * 3, dtype=np.float64)
        me.vertices.foreach_get("co", co)
        tris = np.empty(m * 3, dtype=np.int64)
        me.loop_triangles.foreach_get("vertices", tris)
    finally:
        ob_eval.to_mesh_clear()
    co = co.reshape(-1, 3)
    tris = tris.reshape(-1, 3)
    mw = np.array(ob_eval.matrix_world, dtype=np.float64)
    co = co @ mw[:3, :3].T + mw[:3, 3]
    if np.linalg.det(mw[:3, :3]) < 0:
        tris = tris[:, ::-1].copy()
    if len(tris):
        a, b, c = co[tris[:, 0]], co[tris[:, 1]], co[tris[:, 2]]
        area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
        tris = tris[area2 > 1e-12]
    if len(tris):
        # keep only the vertices the triangles use (smaller JSON)
        used, inverse = np.unique(tris.ravel(), return_inverse=True)
        co = co[used]
        tris = inverse.reshape(-1, 3).astype(np.int64)
    else:
        co = co[:0]
    return co, tris


class Supports:
    """The support surfaces: their Tendril obstacles and a BVH over them (Blender space) for
    snapping seeds and scattering them."""

    def __init__(self, context, objects, ground=None, ground_size=40.0):
        depsgraph = context.evaluated_depsgraph_get()
        self.obstacles = []
        self.names = []
        self.warnings = []
        verts, tris = [], []   # for the BVH and scattering (user supports only)
        offset = 0
        for obj in objects:
            co, tr = world_triangles(obj, depsgraph)
            if len(tr) == 0:
                self.warnings.append(f"{obj.name}: no faces, not a support")
                continue
            self.obstacles.append({
                "name": obj.name,
                "type": "mesh",
                "vertices": convert.rounded(convert.to_tendril(co)),
                "triangles": tr.ravel().tolist(),
            })
            self.names.append(obj.name)
            verts.append(co)
            tris.append(tr + offset)
            offset += len(co)
        self.verts = np.concatenate(verts) if verts else np.zeros((0, 3))
        self.tris = np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)
        self.ground = ground
        if ground is not None:
            cx, cy, h = float(ground[0]), float(ground[1]), float(ground[2])
            name = "ground"
            while name in self.names:
                name += "-tendril"
            self.obstacles.append({
                "name": name, "type": "plane", "size": [ground_size, ground_size],
                "position": convert.vec_to_tendril((cx, cy, h)),
            })
        self.bvh = None
        if len(self.tris):
            self.bvh = BVHTree.FromPolygons([tuple(v) for v in self.verts.tolist()],
                                            [tuple(t) for t in self.tris.tolist()], all_triangles=True)

    def __bool__(self):
        return bool(self.obstacles)

    def nearest(self, point):
        """(location, normal) of the closest support point in Blender space (the ground plane
        included), or None."""
        best = None
        if self.bvh is not None:
            loc, nrm, _i, dist = self.bvh.find_nearest(Vector(point))
            if loc is not None:
                best = (dist, Vector(loc), Vector(nrm).normalized())
        if self.ground is not None:
            h = float(self.ground[2])
            dist = abs(point[2] - h)
            if best is None or dist < best[0]:
                best = (dist, Vector((point[0], point[1], h)), Vector((0.0, 0.0, 1.0)))
        return None if best is None else (best[1], best[2])

    def scatter(self, count, seed):
        """`count` points area-weighted on the selected supports' faces that do not face down,
        deterministic in `seed`: [(location, normal)] in Blender space."""
        if len(self.tris) == 0:
            return []
        a, b, c = (self.verts[self.tris[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a)
        area = np.linalg.norm(cross, axis=1)
        normal = cross / np.maximum(area, 1e-300)[:, None]
        weight = np.where(normal[:, 2] > -0.1, area, 0.0)
        if weight.sum() <= 0:
            return []
        rng = np.random.default_rng(seed)
        pick = rng.choice(len(weight), size=count, p=weight / weight.sum())
        r1 = np.sqrt(rng.random(count))
        r2 = rng.random(count)
        pts = (1 - r1)[:, None] * a[pick] + (r1 * (1 - r2))[:, None] * b[pick] + (r1 * r2)[:, None] * c[pick]
        return [(Vector(p), Vector(n)) for p, n in zip(pts.tolist(), normal[pick].tolist())]


def seed_points(supports, cursor, placement, count, spread, seed, snap, align):
    """Seed positions and growth directions (Blender space) for `count` plants."""
    up = Vector((0.0, 0.0, 1.0))
    out = []
    if placement == 'SCATTER':
        pts = supports.scatter(count, seed)
        if not pts:
            raise UserError("Scatter needs selected supports with faces that do not face down")
        for loc, nrm in pts:
            out.append((loc + nrm * SEED_OFFSET, nrm if align else up))
        return out
    rng = np.random.default_rng(seed)
    for i in range(count):
        p = Vector(cursor)
        if i > 0 and spread > 0:
            r = spread * math.sqrt(rng.random())
            t = 2 * math.pi * rng.random()
            p = p + Vector((r * math.cos(t), r * math.sin(t), 0.0))
        direction = up
        if snap:
            hit = supports.nearest(p)
            if hit is None:
                raise UserError("No support surface to put the seed on (select a mesh or enable Ground)")
            loc, nrm = hit
            p = loc + nrm * SEED_OFFSET
            if align:
                direction = nrm
        out.append((p, direction))
    return out


def lights(context):
    """The scene's lights that render, as Tendril lights (phototropism)."""
    out = []
    for obj in context.scene.objects:
        if obj.type != 'LIGHT' or obj.hide_render or not obj.visible_get():
            continue
        light = obj.data
        mw = obj.matrix_world
        if light.type == 'SUN':
            d = (mw.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
            if d.length < 0.5:
                continue
            entry = {"type": "directional", "direction": convert.vec_to_tendril(d)}
            angle = math.degrees(getattr(light, "angle", 0.0)) / 2
            if angle > 0.01:
                entry["angular_radius"] = min(45.0, round(angle, 3))
            out.append(entry)
        else:
            out.append({"type": "point", "position": convert.vec_to_tendril(mw.translation)})
    return out


def stored_strokes(scene):
    """The attractor strokes the Paint Attractors operator stored on the scene (Tendril
    coordinates, scene-format strokes)."""
    settings = getattr(scene, "tendril", None)
    text = getattr(settings, "strokes_json", "") if settings is not None else ""
    if not text:
        return []
    try:
        strokes = json.loads(text)
    except ValueError:
        return []
    return strokes if isinstance(strokes, list) else []


def document(seed, steps, obstacles, plants, radial_segments=8, subdivisions=3, light_list=None,
             strokes=None, wind=None):
    env = {"obstacles": obstacles}
    if light_list:
        env["lights"] = light_list
    if strokes:
        env["strokes"] = strokes
    if wind:
        env["wind"] = wind
    return {
        "tendril": 1,
        "description": "Grown by the Tendril Blender add-on",
        "seed": int(seed),
        "steps": int(steps),
        "environment": env,
        "plants": plants,
        "output": {"radial_segments": int(radial_segments), "subdivisions": int(subdivisions)},
    }

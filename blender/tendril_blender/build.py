"""Blender meshes, materials and images from a tendril.Model (Session.mesh()).

One Blender object per Tendril object (plant), its parts (bark, leaves-0, ...) concatenated in
order with one material slot per distinct material, so that the object's vertices are exactly the
concatenation of its parts' vertices -- the order Session.wind_frames() poses them in (shape keys).
"""

import hashlib
import json
import os
import tempfile

import bpy
import numpy as np

from . import convert

# Part.uvs follow Tendril's PlantModel convention (origin at the image's bottom-left, as in OBJ
# and in Blender); glTF files flip them on export.  Set to True if the module hands out glTF uvs.
FLIP_V = False

# Custom properties on the objects the add-on creates (docs/blender.md).
PROP_SCENE = "tendril_scene"        # the scene document (JSON) that grew the object
PROP_OBJECT = "tendril_object"      # index of the object in Session.mesh().objects
PROP_PLANT = "tendril_plant"        # the plant's name in the scene document
PROP_MODEL = "tendril_model"        # climb, particles, lsystem, graph
PROP_ORIGIN = "tendril_origin"      # world position (Blender) the mesh is relative to
PROP_BASE_DIR = "tendril_base_dir"  # base_dir the Session was opened with
PROP_VERSION = "tendril_version"    # tendril.version() that grew it
PROP_WIND = "tendril_wind"          # the wind animation's settings (JSON), once animated


def field(rec, key, default=None):
    """A Material/Image record's field: the module hands out dicts (or objects with attributes)."""
    if isinstance(rec, dict):
        return rec.get(key, default)
    return getattr(rec, key, default)


def object_name(rec):
    """A Model.objects entry is (name, parts) (or an object with .name and .parts)."""
    return rec[0] if isinstance(rec, tuple) else rec.name


def object_parts(rec):
    return rec[1] if isinstance(rec, tuple) else rec.parts


def is_tendril_object(obj):
    return obj is not None and obj.type == 'MESH' and PROP_SCENE in obj


# --- images and materials -----------------------------------------------------------------

def _image_name(spec, index):
    spec = str(spec or "")
    base = spec.split(":", 1)[-1] if spec else f"image-{index}"
    base = os.path.splitext(os.path.basename(base.replace("\\", "/")))[0] or f"image-{index}"
    return f"Tendril {base}"


def image_from_record(rec, index):
    """A packed bpy image holding rec.data (PNG/JPEG bytes); an identical one is reused."""
    data = bytes(field(rec, "data", b""))
    digest = hashlib.sha1(data).hexdigest()
    for img in bpy.data.images:
        if img.get("tendril_digest") == digest and img.packed_file is not None:
            return img
    ext = ".jpg" if "jpeg" in str(field(rec, "mime_type", "")).lower() else ".png"
    name = _image_name(field(rec, "spec", ""), index)
    with tempfile.TemporaryDirectory(prefix="tendril-blender-") as tmp:
        path = os.path.join(tmp, "".join(c if c.isalnum() or c in "-_." else "_" for c in name) + ext)
        with open(path, "wb") as f:
            f.write(data)
        img = bpy.data.images.load(path, check_existing=False)
        img.pack()
    img.name = name
    # The packed data is what is used; the path only names it (e.g. for File > External Data >
    # Unpack Resources).
    img.filepath_raw = "//textures/" + os.path.basename(path)
    img["tendril_digest"] = digest
    img["tendril_spec"] = str(field(rec, "spec", ""))
    return img


def _mean_colour(img):
    """Alpha-weighted mean colour of an image, for the viewport's solid colour."""
    try:
        w, h = img.size
        if w * h == 0 or w * h > 4096 * 4096:
            return None
        px = np.empty(w * h * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        px = px.reshape(-1, 4)
        a = px[:, 3]
        if a.sum() <= 0:
            return None
        rgb = (px[:, :3] * a[:, None]).sum(axis=0) / a.sum()
        return [float(c) for c in rgb]
    except Exception:
        return None


def _material_key(m, image_digest):
    rec = {
        "kind": str(field(m, "kind", "")), "name": str(field(m, "name", "")),
        "base_color": [round(float(c), 5) for c in field(m, "base_color", (1, 1, 1, 1))],
        "roughness": round(float(field(m, "roughness", 0.5)), 5), "metallic": round(float(field(m, "metallic", 0)), 5),
        "alpha_mask": bool(field(m, "alpha_mask", False)), "double_sided": bool(field(m, "double_sided", False)),
        "repeat": bool(field(m, "repeat", True)), "image": image_digest,
    }
    return hashlib.sha1(json.dumps(rec, sort_keys=True).encode()).hexdigest()


def material_from_record(m, images):
    """A bpy material for a tendril Material: Principled BSDF, the image (times the base colour)
    as base colour, alpha clip at 0.5 for alpha-masked (leaf) materials.  `images` maps image
    index -> bpy image (built lazily by the caller).  An identical material is reused."""
    kind = str(field(m, "kind", ""))
    name = str(field(m, "name", kind or "material"))
    image_index = field(m, "image", -1)
    image_index = -1 if image_index is None else int(image_index)
    img = images(image_index) if image_index >= 0 else None
    key = _material_key(m, img.get("tendril_digest") if img is not None else None)
    for mat in bpy.data.materials:
        if mat.get("tendril_key") == key:
            return mat

    mat = bpy.data.materials.new(f"Tendril {name}")
    mat["tendril_key"] = key
    mat["tendril_kind"] = kind
    base = [float(c) for c in field(m, "base_color", (1.0, 1.0, 1.0, 1.0))]
    roughness = float(field(m, "roughness", 0.5))
    metallic = float(field(m, "metallic", 0.0))
    if len(base) == 3:
        base.append(1.0)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (400, 0)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (100, 0)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    bsdf.inputs["Base Color"].default_value = base
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic

    alpha_socket = None
    if img is not None:
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.location = (-500, 100)
        tex.image = img
        tex.label = img.name
        # Bark tiles along the stem; a leaf blade's texture does not ('repeat' false).
        tex.extension = 'REPEAT' if field(m, "repeat", True) else 'EXTEND'
        colour = tex.outputs["Color"]
        if any(abs(c - 1.0) > 1e-4 for c in base[:3]):
            mix = nt.nodes.new("ShaderNodeMixRGB")
            mix.location = (-200, 150)
            mix.blend_type = 'MULTIPLY'
            mix.inputs["Fac"].default_value = 1.0
            mix.inputs["Color2"].default_value = base
            nt.links.new(colour, mix.inputs["Color1"])
            colour = mix.outputs["Color"]
        nt.links.new(colour, bsdf.inputs["Base Color"])
        alpha_socket = tex.outputs["Alpha"]
        if base[3] < 1.0:
            mul = nt.nodes.new("ShaderNodeMath")
            mul.operation = 'MULTIPLY'
            mul.location = (-200, -150)
            mul.inputs[1].default_value = base[3]
            nt.links.new(alpha_socket, mul.inputs[0])
            alpha_socket = mul.outputs[0]
        mean = _mean_colour(img)
        viewport = [mean[i] * base[i] for i in range(3)] if mean else base[:3]
    else:
        viewport = base[:3]
        if base[3] < 1.0:
            bsdf.inputs["Alpha"].default_value = base[3]

    if bool(field(m, "alpha_mask", False)):
        if alpha_socket is not None:
            # Eevee clips with blend_method/alpha_threshold; Cycles has no alpha clip, so the
            # threshold is also a node: the same cut-out leaves in both engines.
            clip = nt.nodes.new("ShaderNodeMath")
            clip.operation = 'GREATER_THAN'
            clip.label = "Alpha clip 0.5"
            clip.location = (-200, -300)
            clip.inputs[1].default_value = 0.5
            nt.links.new(alpha_socket, clip.inputs[0])
            nt.links.new(clip.outputs[0], bsdf.inputs["Alpha"])
        if hasattr(mat, "blend_method"):
            mat.blend_method = 'CLIP'
        if hasattr(mat, "alpha_threshold"):
            mat.alpha_threshold = 0.5
        if hasattr(mat, "shadow_method"):
            mat.shadow_method = 'CLIP'
    elif alpha_socket is not None and base[3] < 1.0:
        nt.links.new(alpha_socket, bsdf.inputs["Alpha"])
        if hasattr(mat, "blend_method"):
            mat.blend_method = 'BLEND'

    mat.use_backface_culling = not bool(field(m, "double_sided", False))
    mat.diffuse_color = (*viewport, 1.0)
    mat.roughness = roughness
    mat.metallic = metallic
    return mat


class MaterialCache:
    """Builds a model's images and materials once, on first use."""

    def __init__(self, model):
        self.model = model
        self._images = {}
        self._materials = {}

    def image(self, i):
        if i not in self._images:
            images = self.model.images
            if i < 0 or i >= len(images):
                return None
            self._images[i] = image_from_record(images[i], i)
        return self._images[i]

    def material(self, i):
        if i not in self._materials:
            materials = self.model.materials
            if i < 0 or i >= len(materials):
                return None
            self._materials[i] = material_from_record(materials[i], self.image)
        return self._materials[i]


# --- meshes ---------------------------------------------------------------------------------

def part_arrays(obj_rec):
    """(positions, normals, uvs, triangles, material index per triangle, part sizes) of one
    tendril Object, its parts concatenated, still in Tendril coordinates."""
    pos, nrm, uvs, tris, mats, sizes = [], [], [], [], [], []
    offset = 0
    for part in object_parts(obj_rec):
        p = np.asarray(part.positions, dtype=np.float32).reshape(-1, 3)
        n = len(p)
        idx = np.asarray(part.indices, dtype=np.int64).reshape(-1, 3)
        pn = np.asarray(part.normals, dtype=np.float32).reshape(-1, 3)
        pu = np.asarray(part.uvs, dtype=np.float32).reshape(-1, 2)
        pos.append(p)
        nrm.append(pn if len(pn) == n else np.zeros((n, 3), np.float32))
        uvs.append(pu if len(pu) == n else np.zeros((n, 2), np.float32))
        tris.append(idx + offset)
        mats.append(np.full(len(idx), int(part.material), dtype=np.int64))
        sizes.append(n)
        offset += n
    if not pos:
        z3 = np.zeros((0, 3), np.float32)
        return z3, z3, np.zeros((0, 2), np.float32), np.zeros((0, 3), np.int64), np.zeros(0, np.int64), []
    return (np.concatenate(pos), np.concatenate(nrm), np.concatenate(uvs), np.concatenate(tris),
            np.concatenate(mats), sizes)


def rest_positions(obj_rec, origin):
    """The object's vertex positions in Blender coordinates relative to `origin`."""
    parts = object_parts(obj_rec)
    pos = np.concatenate([np.asarray(p.positions, dtype=np.float32).reshape(-1, 3) for p in parts]) \
        if len(parts) else np.zeros((0, 3), np.float32)
    return convert.from_tendril(pos) - np.asarray(origin, dtype=np.float32)


def new_mesh(name, obj_rec, origin, materials):
    """A bpy mesh for one tendril Object, relative to `origin` (Blender world coordinates);
    `materials` is a MaterialCache.  Returns None when the object has no triangles."""
    pos_t, nrm_t, uvs, tris, mats, _ = part_arrays(obj_rec)
    n, m = len(pos_t), len(tris)
    if n == 0 or m == 0:
        return None
    if tris.min() < 0 or tris.max() >= n:
        raise ValueError(f"object {name}: triangle index out of range (module bug)")
    pos = convert.from_tendril(pos_t) - np.asarray(origin, dtype=np.float32)
    nrm = convert.from_tendril(nrm_t)
    length = np.linalg.norm(nrm, axis=1)
    bad = length < 1e-12
    nrm[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    nrm /= length[:, None]
    if FLIP_V:
        uvs = uvs.copy()
        uvs[:, 1] = 1.0 - uvs[:, 1]

    me = bpy.data.meshes.new(name)
    # One material slot per distinct material, in order of first use.
    used = []
    for i in mats.tolist():
        if i not in used:
            used.append(i)
    slot = {mi: s for s, mi in enumerate(used)}
    for mi in used:
        me.materials.append(materials.material(mi))

    tri32 = tris.astype(np.int32)
    me.vertices.add(n)
    me.vertices.foreach_set("co", pos.ravel())
    me.loops.add(3 * m)
    me.loops.foreach_set("vertex_index", tri32.ravel())
    me.polygons.add(m)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * m, 3, dtype=np.int32))
    try:
        me.polygons.foreach_set("loop_total", np.full(m, 3, dtype=np.int32))
    except (AttributeError, TypeError, RuntimeError):
        pass  # read-only in newer Blender: derived from loop_start
    me.polygons.foreach_set("material_index", np.array([slot[i] for i in mats.tolist()], dtype=np.int32))
    me.polygons.foreach_set("use_smooth", np.ones(m, dtype=bool))
    uv_layer = me.uv_layers.new(name="UVMap")
    uv_layer.data.foreach_set("uv", uvs[tri32.ravel()].astype(np.float32).ravel())
    me.update(calc_edges=True)
    me.validate(clean_customdata=False)
    if hasattr(me, "use_auto_smooth"):
        me.use_auto_smooth = True  # Blender < 4.1: needed for custom normals
    me.normals_split_custom_set_from_vertices(nrm)
    me.update()
    return me


def origin_of(doc, plant_name, obj_rec):
    """Blender world position for the object's origin: its plant's seed position."""
    for p in doc.get("plants", []):
        if p.get("name") == plant_name and "position" in p:
            return np.asarray(convert.vec_from_tendril(p["position"]), dtype=np.float32)
    pos = rest_positions(obj_rec, (0.0, 0.0, 0.0))
    if len(pos) == 0:
        return np.zeros(3, np.float32)
    lo = pos.min(axis=0)
    hi = pos.max(axis=0)
    return np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]], dtype=np.float32)


def plant_name_for(doc, obj_rec, index):
    names = [p.get("name") for p in doc.get("plants", [])]
    name = object_name(obj_rec)
    if name in names:
        return name
    return names[index] if index < len(names) else name


def build_objects(context, model, doc, base_dir, version, collection=None, scale=1.0):
    """Creates one object per tendril Object with geometry; returns them.  On failure, removes
    what it created and re-raises."""
    collection = collection or context.collection or context.scene.collection
    doc_json = json.dumps(doc, separators=(",", ":"))
    materials = MaterialCache(model)
    created = []
    try:
        for i, rec in enumerate(model.objects):
            plant = plant_name_for(doc, rec, i)
            origin = origin_of(doc, plant, rec)
            me = new_mesh(object_name(rec) or plant or f"plant{i}", rec, origin, materials)
            if me is None:
                continue
            obj = bpy.data.objects.new(me.name, me)
            collection.objects.link(obj)
            created.append(obj)
            obj.location = [float(c) for c in origin]
            if scale != 1.0:
                obj.scale = (scale, scale, scale)
            obj[PROP_SCENE] = doc_json
            obj[PROP_OBJECT] = i
            obj[PROP_PLANT] = plant
            obj[PROP_MODEL] = next((str(p.get("model", "climb")) for p in doc.get("plants", [])
                                    if p.get("name") == plant), "")
            obj[PROP_ORIGIN] = [float(c) for c in origin]
            obj[PROP_BASE_DIR] = base_dir
            obj[PROP_VERSION] = version
    except BaseException:
        remove_objects(created)
        raise
    return created


def replace_mesh(obj, rec, model_materials):
    """Gives `obj` a new mesh built from `rec` at its stored origin (keeps the old one if it has
    other users).  Returns the new mesh."""
    origin = [float(c) for c in obj.get(PROP_ORIGIN, (0.0, 0.0, 0.0))]
    me = new_mesh(obj.data.name, rec, origin, model_materials)
    if me is None:
        raise ValueError(f"{obj.name}: the regrown plant has no geometry")
    old = obj.data
    obj.data = me
    if old.users == 0:
        bpy.data.meshes.remove(old)
    return me


def remove_objects(objs):
    for obj in objs:
        try:
            me = obj.data
            bpy.data.objects.remove(obj, do_unlink=True)
            if me is not None and me.users == 0:
                bpy.data.meshes.remove(me)
        except ReferenceError:
            pass

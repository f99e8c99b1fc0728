"""Wind animation as shape keys: one key per frame of Session.wind_frames(), keyed so that
exactly one key is fully on at each frame, looping (the clip's frame `frames` is its frame 0)."""

import os

import bpy
import numpy as np

from . import convert

KEY_PREFIX = "wind_"
MODIFIER_NAME = "Tendril wind"   # the Mesh Cache modifier of the MESH_CACHE method


def object_frames(frames, part_ranges):
    """Per clip frame, the concatenated positions (Tendril) of the parts in `part_ranges`
    (indices into each frame's flat list of parts)."""
    out = []
    for frame in frames:
        arrays = [np.asarray(frame[i], dtype=np.float32).reshape(-1, 3) for i in part_ranges]
        out.append(np.concatenate(arrays) if arrays else np.zeros((0, 3), np.float32))
    return out


def drop_closing_frame(frames, expected):
    """wind_frames(seconds, fps) hands back round(seconds * fps) frames, the loop's closing frame
    (equal to frame 0) left out; should it include it, drop it."""
    if len(frames) == expected + 1 and expected > 0:
        return frames[:-1]
    return frames


def clear(obj):
    """Removes the add-on's wind animation from `obj`: its shape keys and their action, or its
    Mesh Cache modifier and that F-curve (the cache file stays on disk)."""
    me = obj.data
    keys = me.shape_keys
    if keys is not None:
        ad = keys.animation_data
        if ad is not None and ad.action is not None and ad.action.get("tendril_wind"):
            action = ad.action
            ad.action = None
            if action.users == 0:
                bpy.data.actions.remove(action)
        obj.shape_key_clear()
    mod = obj.modifiers.get(MODIFIER_NAME)
    if mod is not None:
        obj.modifiers.remove(mod)
    ad = obj.animation_data
    if ad is not None and ad.action is not None:
        action = ad.action
        for fc in [fc for fc in action.fcurves if fc.data_path.startswith(f'modifiers["{MODIFIER_NAME}"]')]:
            action.fcurves.remove(fc)
        if action.get("tendril_wind") and not action.fcurves:
            ad.action = None
            if action.users == 0:
                bpy.data.actions.remove(action)
    if "tendril_wind" in obj:
        del obj["tendril_wind"]


def _set_keyframes(fcurve, points):
    fcurve.keyframe_points.add(len(points))
    fcurve.keyframe_points.foreach_set("co", np.asarray(points, dtype=np.float32).ravel())
    for kp in fcurve.keyframe_points:
        kp.interpolation = 'LINEAR'
    fcurve.update()


def animate(obj, positions, frame_start, frame_step, cyclic=True):
    """Shape keys `wind_000`... on `obj` from `positions` (list of (n, 3) arrays in Blender
    object space, one per clip frame), keyframed at frame_start + k * frame_step, looping."""
    me = obj.data
    clear(obj)
    n = len(positions)
    obj.shape_key_add(name="Basis", from_mix=False)
    keys = []
    width = max(3, len(str(n - 1)))
    for k, pos in enumerate(positions):
        kb = obj.shape_key_add(name=f"{KEY_PREFIX}{k:0{width}d}", from_mix=False)
        kb.data.foreach_set("co", np.ascontiguousarray(pos, dtype=np.float32).ravel())
        kb.slider_min = 0.0
        kb.slider_max = 1.0
        kb.value = 0.0
        keys.append(kb)
    key = me.shape_keys
    key.use_relative = True
    if key.animation_data is None:
        key.animation_data_create()
    action = bpy.data.actions.new(f"{obj.name} wind")
    action["tendril_wind"] = True
    key.animation_data.action = action
    for k, kb in enumerate(keys):
        fc = action.fcurves.new(data_path=f'key_blocks["{kb.name}"].value')
        # On at clip frame k, off at its neighbours (modulo n), and the same value at both ends
        # of the loop so that the Cycles modifier repeats it seamlessly.
        at_ends = 1.0 if k == 0 else 0.0
        frames = {0: at_ends, n: at_ends}
        if n > 1:
            frames[(k - 1) % n] = 0.0
            if k + 1 < n:
                frames[k + 1] = 0.0
        frames[k] = 1.0
        points = sorted((frame_start + j * frame_step, v) for j, v in frames.items())
        _set_keyframes(fc, points)
        if cyclic:
            fc.modifiers.new('CYCLES')
    return keys


def object_space(positions_tendril, obj):
    origin = np.asarray(obj.get("tendril_origin", (0.0, 0.0, 0.0)), dtype=np.float32)
    return convert.from_tendril(positions_tendril) - origin


# --- Mesh Cache (PC2) ---------------------------------------------------------------------------
# Shape keys keep every frame in the .blend (frames x vertices x 12 bytes); for heavy plants a
# point cache file read by a Mesh Cache modifier is lighter.


def write_pc2(path, positions, sample_rate=1.0):
    """A PC2 point cache: the frames in `positions` plus the loop's closing frame (== frame 0),
    so that reading it at fractional frames n-1..n blends back into frame 0."""
    import struct
    n_points = len(positions[0]) if positions else 0
    samples = list(positions) + [positions[0]]
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "wb") as f:
        f.write(struct.pack("<12siiffi", b"POINTCACHE2\0", 1, n_points, 0.0, float(sample_rate), len(samples)))
        for p in samples:
            f.write(np.ascontiguousarray(p, dtype="<f4").tobytes())


def animate_mesh_cache(obj, path, stored_path, n, frame_start, frame_step, cyclic=True):
    """A Mesh Cache modifier reading `path` (written by write_pc2 with n frames), its frame
    keyed linearly 0 -> n over one loop, repeating."""
    clear(obj)
    mod = obj.modifiers.new(MODIFIER_NAME, 'MESH_CACHE')
    mod.cache_format = 'PC2'
    mod.filepath = stored_path
    mod.deform_mode = 'OVERWRITE'
    mod.interpolation = 'LINEAR'
    mod.time_mode = 'FRAME'
    mod.play_mode = 'CUSTOM'
    mod.eval_frame = 0.0
    if obj.animation_data is None:
        obj.animation_data_create()
    action = obj.animation_data.action
    if action is None:
        action = bpy.data.actions.new(f"{obj.name} wind")
        action["tendril_wind"] = True
        obj.animation_data.action = action
    fc = action.fcurves.new(data_path=f'modifiers["{MODIFIER_NAME}"].eval_frame')
    _set_keyframes(fc, [(frame_start, 0.0), (frame_start + n * frame_step, float(n))])
    if cyclic:
        fc.modifiers.new('CYCLES')
    return mod

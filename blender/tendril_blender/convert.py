"""Coordinate conversion between Blender (Z-up) and Tendril (Y-up).

Both are right-handed and in metres.  The conversion is a rotation of -90 degrees about +X:

    Blender (x, y, z)  ->  Tendril (x, z, -y)
    Tendril (x, y, z)  ->  Blender (x, -z, y)

A rotation keeps lengths, normals (they convert the same way as points) and the winding of
triangles.  Everything here works on numpy arrays of shape (n, 3) or on single 3-sequences and
does not import bpy, so it can be tested without Blender.
"""

import numpy as np


def to_tendril(points):
    """Blender (n, 3) -> Tendril (n, 3), as a new float64 array."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty_like(p)
    out[:, 0] = p[:, 0]
    out[:, 1] = p[:, 2]
    out[:, 2] = -p[:, 1]
    return out


def from_tendril(points, dtype=np.float32):
    """Tendril (n, 3) -> Blender (n, 3), as a new array of `dtype`."""
    p = np.asarray(points).reshape(-1, 3)
    out = np.empty(p.shape, dtype=dtype)
    out[:, 0] = p[:, 0]
    out[:, 1] = -p[:, 2]
    out[:, 2] = p[:, 1]
    return out


def vec_to_tendril(v):
    """One Blender vector -> a Tendril [x, y, z] list of Python floats (for JSON)."""
    x, y, z = (float(c) for c in v)
    return [x, z, -y]


def vec_from_tendril(v):
    """One Tendril vector -> a Blender (x, y, z) tuple of Python floats."""
    x, y, z = (float(c) for c in v)
    return (x, -z, y)


def rounded(array, decimals=6):
    """A flat list of Python floats rounded to `decimals` (micrometres for metres): compact in
    the scene JSON stored on the grown objects, and exactly what was grown (JSON round-trips
    Python floats exactly)."""
    return np.round(np.asarray(array, dtype=np.float64).ravel(), decimals).tolist()

"""Tendril: plants that grow, climb, move in the wind and can be edited while they grow.

The Session is the one API (docs/python.md)::

    import tendril
    s = tendril.Session.open("examples/scenes/default.json")
    s.run()                              # grows as `tendril grow` does
    ivy = s.plant(0)                     # skeleton arrays (numpy views)
    s.export("out/plant.glb")

Tendril's frame is y up, in metres.
"""

from __future__ import annotations

from ._tendril import (Error, Model, Part, Plant, Session, TendrilWarning, models, presets, set_threads, threads,
                       version)

__all__ = [
    "Error",
    "Model",
    "Part",
    "Plant",
    "Session",
    "TendrilWarning",
    "mesh_obstacle",
    "models",
    "presets",
    "set_threads",
    "threads",
    "version",
]

__version__ = version()


# Annotations are strings (from __future__ above): typing is not imported, which keeps
# `import tendril` quick.


def _error(location: str, message: str) -> Error:
    """A tendril.Error raised by the Python side, shaped like the module's own."""
    e = Error(f"<python>:{location}: {message}")
    e.source, e.location, e.message = "<python>", location, message
    return e


def _flat(values: Any, name: str, width: int, kind: type) -> list:
    """A (n, width) array-like as a flat list of `kind`, checked for shape."""
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy is a dependency of the tests, not of the module
        rows = [list(r) for r in values]
        if any(len(r) != width for r in rows):
            raise _error(name, f"expected rows of {width} values")
        return [kind(x) for r in rows for x in r]
    a = np.asarray(values)
    if a.ndim != 2 or a.shape[1] != width:
        raise _error(name, f"expected an array of shape (n, {width}), got {a.shape}")
    return a.astype(np.float64 if kind is float else np.int64).ravel().tolist()


def mesh_obstacle(
    vertices: Any,
    triangles: Any,
    name: str = "mesh",
    position: Sequence[float] = (0.0, 0.0, 0.0),
    rotation: Sequence[float] = (0.0, 0.0, 0.0),
    color: Optional[Sequence[float]] = None,
) -> dict:
    """A scene obstacle (for the scene dict's environment.obstacles) from arrays.

    vertices: (n, 3) numbers in Tendril's frame (y up, metres); triangles: (m, 3) vertex
    indices. position and rotation (degrees about x, y, z) place the mesh, as for every
    obstacle. The scene reader checks the values (an index out of range is an Error naming
    the obstacle's pointer).
    """
    o = {
        "name": name,
        "type": "mesh",
        "vertices": _flat(vertices, "vertices", 3, float),
        "triangles": _flat(triangles, "triangles", 3, int),
        "position": [float(x) for x in position],
        "rotation": [float(x) for x in rotation],
    }
    if color is not None:
        o["color"] = [float(x) for x in color]
    return o


def _import_obstacle(
    self: Session,
    path: str,
    name: str = "",
    position: Optional[Sequence[float]] = None,
    rotation: Optional[Sequence[float]] = None,
    scale: Any = None,
    color: Optional[Sequence[float]] = None,
) -> int:
    """Imports a support mesh file (OBJ, glTF/GLB, PLY, STL, FBX, ...) as a new obstacle, as the
    `add_obstacle` edit (undoable; position and rotation as for `move_obstacle`, scale a number
    or [x, y, z]). Returns the obstacle's index."""
    edit: dict = {"edit": "add_obstacle", "path": str(path)}
    if name:
        edit["name"] = name
    for key, value in (("position", position), ("rotation", rotation), ("color", color)):
        if value is not None:
            edit[key] = [float(x) for x in value]
    if scale is not None:
        edit["scale"] = float(scale) if isinstance(scale, (int, float)) else [float(x) for x in scale]
    self.edit(edit)
    return self.obstacle_count - 1


Session.import_obstacle = _import_obstacle  # type: ignore[attr-defined]

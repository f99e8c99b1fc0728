"""Finding and loading the compiled `tendril` Python module.

Order (docs/blender.md):
1. `import tendril` as is (installed into Blender's Python, or already on sys.path);
2. the add-on preferences' "Module path";
3. the environment variable TENDRIL_PYTHON_PATH (one or more directories, os.pathsep-separated).

Each directory may be the one that contains the `tendril` package (e.g. <repo>/build/ci/python)
or the package directory itself (<repo>/build/ci/python/tendril).  Nothing here raises: the
result is either the module or a readable explanation that the panel shows.
"""

import importlib
import os
import sys

ENV_VAR = "TENDRIL_PYTHON_PATH"

_module = None      # the loaded module, once found
_status = None      # one-line explanation when it was not found (None: not tried yet)
_attempts = []      # what was tried, for the panel


def _looks_like_tendril(mod):
    # A directory called `tendril` without __init__ (e.g. the C++ sources' src/tendril) imports
    # as a namespace package; only the real module has Session.
    return hasattr(mod, "Session") and hasattr(mod, "presets")


def _forget_failed_import():
    for name in list(sys.modules):
        if name == "tendril" or name.startswith("tendril."):
            del sys.modules[name]


def _try_import(where):
    try:
        mod = importlib.import_module("tendril")
    except Exception as e:  # ImportError, or an error inside the module's own import
        _forget_failed_import()
        _attempts.append(f"{where}: {type(e).__name__}: {e}")
        return None
    if not _looks_like_tendril(mod):
        path = getattr(mod, "__file__", None) or list(getattr(mod, "__path__", []))
        _forget_failed_import()
        _attempts.append(f"{where}: found a 'tendril' at {path} that is not Tendril's Python module")
        return None
    return mod


def _normalise_dir(d):
    d = os.path.abspath(os.path.expanduser(d))
    # The package directory itself: use its parent.
    if os.path.basename(os.path.normpath(d)) == "tendril" and os.path.isfile(os.path.join(d, "__init__.py")):
        d = os.path.dirname(os.path.normpath(d))
    return d


def _try_dir(d, where):
    d = _normalise_dir(d)
    if not os.path.isdir(d):
        _attempts.append(f"{where}: {d} is not a directory")
        return None
    if not os.path.isdir(os.path.join(d, "tendril")):
        _attempts.append(f"{where}: {d} has no 'tendril' package")
        return None
    added = d not in sys.path
    if added:
        sys.path.insert(0, d)
    mod = _try_import(f"{where} ({d})")
    if mod is None and added:
        try:
            sys.path.remove(d)
        except ValueError:
            pass
    return mod


def _preference_path():
    try:
        import bpy
        addon = bpy.context.preferences.addons.get(__package__)
        if addon is not None and addon.preferences is not None:
            return addon.preferences.module_path.strip()
    except Exception:
        pass
    return ""


def reset():
    """Forget the last result (e.g. after the preferences' module path changed)."""
    global _module, _status
    if _module is None:
        _status = None


def load():
    """The `tendril` module, or None (then `status()` says why)."""
    global _module, _status
    if _module is not None:
        return _module
    if _status is not None:
        return None
    _attempts.clear()
    mod = _try_import("import tendril")
    if mod is None:
        pref = _preference_path()
        if pref:
            mod = _try_dir(bpy_abspath(pref), "preferences' Module path")
        else:
            _attempts.append("preferences' Module path: not set")
    if mod is None:
        env = os.environ.get(ENV_VAR, "").strip()
        if env:
            for d in env.split(os.pathsep):
                if d.strip():
                    mod = _try_dir(d.strip(), ENV_VAR)
                    if mod is not None:
                        break
        else:
            _attempts.append(f"{ENV_VAR}: not set")
    if mod is None:
        _status = ("Tendril's Python module was not found. Set the add-on preferences' Module path "
                   "to the directory holding the 'tendril' package (e.g. <tendril>/build/ci/python), "
                   f"or {ENV_VAR}, and press Reload.")
        return None
    _module = mod
    _status = ""
    return mod


def bpy_abspath(path):
    try:
        import bpy
        return bpy.path.abspath(path)
    except Exception:
        return path


def status():
    """'' when loaded; else a sentence to show."""
    if load() is not None:
        return ""
    return _status or ""


def attempts():
    """What was tried, one line each (shown in the preferences and the panel)."""
    load()
    return list(_attempts)


def version():
    mod = load()
    if mod is None:
        return ""
    try:
        return str(mod.version())
    except Exception as e:
        return f"? ({e})"


class NotLoaded(Exception):
    """Raised by require(): carries the panel's explanation."""


def require():
    mod = load()
    if mod is None:
        raise NotLoaded(status())
    return mod


def presets(model):
    """tendril.presets(model), or [] when the module is missing or fails."""
    mod = load()
    if mod is None:
        return []
    try:
        return [str(p) for p in mod.presets(model)]
    except Exception:
        return []


def error_types():
    """Exceptions that mean bad input from the module (tendril.Error), for `except`."""
    mod = load()
    err = getattr(mod, "Error", None) if mod is not None else None
    return (err,) if isinstance(err, type) else ()

"""Sweep files: a base plant or scene and the parameters to vary, expanded into a manifest.

A sweep file (docs/batch.md) names a base -- a scene file, a component graph or an L-system
grammar, the latter two wrapped into a one-plant scene -- fixed settings and parameters to vary,
each addressed by a JSON pointer into the resolved scene: value lists, numeric ranges (a step or
a count) and random values within bounds drawn from the sweep's seed. List and range parameters
combine as a cartesian product; random parameters are drawn per variant. `expand()` turns it
into manifest entries, one per variant, each with its full resolved scene and a content key
(sha256 of the canonical inputs and the Tendril version); `write_manifest()` writes them as
`<out>/manifest.jsonl`, atomically.

Reading is strict like every Tendril file: unknown keys (with a suggestion), wrong types and
bad ranges are a `tendril.Error` whose one line names the file and the JSON pointer.
"""

from __future__ import annotations

import copy
import difflib
import hashlib
import itertools
import json
import math
import os
import random
from pathlib import Path

from . import Error, version

SWEEP_VERSION = 1
MANIFEST_VERSION = 1
MAX_VARIANTS = 1_000_000
PREVIEW_DEFAULT = {"width": 256, "height": 192}


def error(source: str, location: str, message: str) -> Error:
    """A tendril.Error shaped like the module's own: str(e) is 'source:location: message'."""
    text = f"{source}:{location}: {message}" if location else f"{source}: {message}"
    e = Error(text)
    e.source, e.location, e.message = source, location, message
    return e


def canonical(value) -> bytes:
    """Canonical JSON (sorted keys, no spaces, UTF-8): what content keys are hashed over."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False).encode()


def sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def escape_token(token: str) -> str:
    return token.replace("~", "~0").replace("/", "~1")


def split_pointer(pointer: str) -> list:
    if pointer == "":
        return []
    if not pointer.startswith("/"):
        raise ValueError('a JSON pointer starts with "/"')
    tokens = pointer[1:].split("/")
    return [t.replace("~1", "/").replace("~0", "~") for t in tokens]


def load_json(path: Path, source: str):
    """A JSON file, strictly: syntax errors as file:line:col, duplicate keys rejected."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise error(source, "", f"cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError:
        raise error(source, "", "is not UTF-8 text") from None

    def pairs(items):
        d = {}
        for k, v in items:
            if k in d:
                raise ValueError(f'duplicate key "{k}"')
            d[k] = v
        return d

    def constant(name):
        raise ValueError(f"{name} is not a JSON number")

    try:
        return json.loads(text, object_pairs_hook=pairs, parse_constant=constant)
    except json.JSONDecodeError as e:
        raise error(source, f"{e.lineno}:{e.colno}", f"syntax error: {e.msg}") from None
    except ValueError as e:
        raise error(source, "", str(e)) from None


def _kind(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    return "object"


def _shown(value) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


class _Reader:
    """Strict reading of one JSON document, errors naming the file and the pointer."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, pointer: str, message: str) -> Error:
        return error(self.source, pointer or "/", message)

    def object(self, value, pointer: str, known: dict) -> dict:
        """Checks value is an object whose keys are in `known` ({key: required}); returns it."""
        if not isinstance(value, dict):
            raise self.fail(pointer, f"expected an object, got {_kind(value)} {_shown(value)}")
        for key in value:
            if key not in known:
                close = difflib.get_close_matches(key, list(known), n=1)
                hint = f' (did you mean "{close[0]}"?)' if close else f" (known keys: {', '.join(sorted(known))})"
                raise self.fail(f"{pointer}/{escape_token(key)}", f'unknown key "{key}"{hint}')
        for key, required in known.items():
            if required and key not in value:
                raise self.fail(pointer, f'missing required key "{key}"')
        return value

    def integer(self, value, pointer: str, lo=None, hi=None) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(pointer, f"expected an integer, got {_kind(value)} {_shown(value)}")
        self._range(value, pointer, lo, hi)
        return value

    def number(self, value, pointer: str, lo=None, hi=None):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(pointer, f"expected a number, got {_kind(value)} {_shown(value)}")
        self._range(value, pointer, lo, hi)
        return value

    def _range(self, value, pointer, lo, hi):
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise self.fail(pointer, f"must be in [{lo if lo is not None else '-inf'}, {hi if hi is not None else 'inf'}], got {value}")

    def boolean(self, value, pointer: str) -> bool:
        if not isinstance(value, bool):
            raise self.fail(pointer, f"expected true or false, got {_kind(value)} {_shown(value)}")
        return value

    def string(self, value, pointer: str, nonempty=True) -> str:
        if not isinstance(value, str):
            raise self.fail(pointer, f"expected a string, got {_kind(value)} {_shown(value)}")
        if nonempty and not value:
            raise self.fail(pointer, "must not be empty")
        return value


def set_pointer(doc, pointer: str, value, create: bool = True):
    """Sets doc at `pointer` (RFC 6901) to value, in place. Missing object keys on the way are
    created as objects; a species given by name ("japanese-ivy") becomes {"base": name} when the
    pointer goes into it, so species keys can be varied. Raises ValueError saying what is wrong."""
    tokens = split_pointer(pointer)
    if not tokens:
        raise ValueError("the empty pointer would replace the whole scene")
    node = doc
    where = ""
    for i, token in enumerate(tokens):
        last = i == len(tokens) - 1
        if isinstance(node, list):
            if not token.isdigit() or (len(token) > 1 and token[0] == "0"):
                raise ValueError(f"{where or '/'} is an array: expected an index, got \"{token}\"")
            k = int(token)
            if k >= len(node):
                raise ValueError(f"{where or '/'} has {len(node)} element{'s' if len(node) != 1 else ''}, no index {k}")
            if last:
                node[k] = value
                return
            child = node[k]
            key = k
        elif isinstance(node, dict):
            if last:
                node[token] = value
                return
            if token not in node:
                if not create:
                    raise ValueError(f'{where or "/"} has no key "{token}"')
                node[token] = {}
            child = node[token]
            key = token
        else:
            raise ValueError(f"{where} is {_kind(node)} {_shown(node)}, not an object or array")
        if isinstance(child, str) and key == "species":
            child = {"base": child}
            node[key] = child
        node = child
        where += "/" + escape_token(token)


def get_pointer(doc, pointer: str):
    node = doc
    for token in split_pointer(pointer):
        if isinstance(node, list) and token.isdigit() and int(token) < len(node):
            node = node[int(token)]
        elif isinstance(node, dict) and token in node:
            node = node[token]
        else:
            raise KeyError(pointer)
    return node


# ---------------------------------------------------------------------------------------------
# Base: a scene, a component graph or a grammar

def _is_preset(value: str, model: str) -> bool:
    from . import presets

    names = presets(model)
    return value in names or any(Path(n).stem == value and not value.endswith(".json") for n in names)


def _base_scene(r: _Reader, base, pointer: str, sweep_dir: Path):
    """(scene dict, base_dir) for the sweep's base."""
    r.object(base, pointer, {"scene": False, "graph": False, "grammar": False})
    given = [k for k in ("scene", "graph", "grammar") if k in base]
    if len(given) != 1:
        raise r.fail(pointer, 'expected exactly one of "scene", "graph" or "grammar"'
                     + (f" (got {', '.join(given)})" if given else ""))
    kind = given[0]
    value = base[kind]
    p = f"{pointer}/{kind}"
    if kind == "scene":
        if isinstance(value, dict):
            return copy.deepcopy(value), sweep_dir
        path = (sweep_dir / r.string(value, p)).resolve()
        if not path.is_file():
            raise r.fail(p, f"scene file {path} does not exist")
        scene = load_json(path, str(path))
        if not isinstance(scene, dict):
            raise error(str(path), "/", "expected a scene object")
        return scene, path.parent
    name = r.string(value, p)
    if kind == "graph":
        if _is_preset(name, "graph") and not (sweep_dir / name).is_file():
            from . import presets

            graph_path = next(Path(n) for n in presets("graph") if Path(n).stem == name or n == name)
        else:
            graph_path = (sweep_dir / name).resolve()
            if not graph_path.is_file():
                raise r.fail(p, f"graph file {graph_path} does not exist (nor is it one of tendril.presets(\"graph\"))")
        plant = {"name": graph_path.stem, "model": "graph", "graph": str(graph_path), "position": [0, 0, 0]}
        return {"tendril": 1, "seed": 1, "steps": 1, "plants": [plant], "output": {}}, sweep_dir
    # grammar: a built-in name or a .ls path
    if name.endswith(".ls") or (sweep_dir / name).is_file():
        grammar_path = (sweep_dir / name).resolve()
        if not grammar_path.is_file():
            raise r.fail(p, f"grammar file {grammar_path} does not exist")
        grammar, stem = str(grammar_path), grammar_path.stem
    else:
        if not _is_preset(name, "lsystem"):
            raise r.fail(p, f'"{name}" is neither a .ls file nor one of tendril.presets("lsystem")')
        grammar, stem = name, name
    plant = {"name": stem, "model": "lsystem", "grammar": grammar, "position": [0, 0, 0]}
    return {"tendril": 1, "seed": 1, "plants": [plant], "output": {}}, sweep_dir


# ---------------------------------------------------------------------------------------------
# Parameters

def _tidy(x):
    """A range value without float noise (0.30000000000000004 -> 0.3)."""
    return x if isinstance(x, int) else float(f"{x:.12g}")


def _range_values(r: _Reader, spec, pointer: str) -> list:
    r.object(spec, pointer, {"from": True, "to": True, "step": False, "count": False})
    lo = r.number(spec["from"], pointer + "/from")
    hi = r.number(spec["to"], pointer + "/to")
    if hi < lo:
        raise r.fail(pointer + "/to", f"must not be below \"from\" ({lo}), got {hi}")
    if ("step" in spec) == ("count" in spec):
        raise r.fail(pointer, 'expected exactly one of "step" or "count"')
    if "step" in spec:
        step = r.number(spec["step"], pointer + "/step")
        if not step > 0:
            raise r.fail(pointer + "/step", f"must be > 0, got {step}")
        n = int(math.floor((hi - lo) / step * (1 + 1e-12) + 1e-9)) + 1
        if n > MAX_VARIANTS:
            raise r.fail(pointer + "/step", f"gives {n} values, more than {MAX_VARIANTS}")
        ints = all(isinstance(v, int) for v in (lo, hi, step))
        return [lo + k * step if ints else _tidy(lo + k * step) for k in range(n)]
    count = r.integer(spec["count"], pointer + "/count", 1, MAX_VARIANTS)
    if count == 1:
        return [lo]
    ints = isinstance(lo, int) and isinstance(hi, int) and (hi - lo) % (count - 1) == 0
    if ints:
        return [lo + k * ((hi - lo) // (count - 1)) for k in range(count)]
    return [_tidy(lo + (hi - lo) * k / (count - 1)) for k in range(count)]


def _random_spec(r: _Reader, spec, pointer: str) -> dict:
    r.object(spec, pointer, {"min": True, "max": True, "integer": False})
    integer = r.boolean(spec.get("integer", False), pointer + "/integer")
    if integer:
        lo = r.integer(spec["min"], pointer + "/min")
        hi = r.integer(spec["max"], pointer + "/max")
    else:
        lo = r.number(spec["min"], pointer + "/min")
        hi = r.number(spec["max"], pointer + "/max")
    if hi < lo:
        raise r.fail(pointer + "/max", f"must not be below \"min\" ({lo}), got {hi}")
    return {"min": lo, "max": hi, "integer": integer}


def draw_random(seed: int, index: int, pointer: str, spec: dict):
    """The random parameter `pointer` of variant `index`: keyed by the sweep seed, the variant
    and the pointer only, so adding a parameter does not change the others' draws."""
    digest = hashlib.sha256(canonical(["tendril-sweep", seed, index, pointer])).digest()
    rng = random.Random(int.from_bytes(digest[:16], "little"))
    if spec["integer"]:
        return rng.randint(spec["min"], spec["max"])
    return float(f"{rng.uniform(spec['min'], spec['max']):.6g}")


# ---------------------------------------------------------------------------------------------
# Referenced files

_PATH_SUFFIXES = (".json", ".ls", ".obj", ".ply", ".stl", ".off", ".glb", ".gltf", ".fbx", ".dae", ".png", ".jpg",
                  ".jpeg", ".tses")


def referenced_files(scene, base_dir: Path) -> dict:
    """{path as written: sha256} for every string in the scene naming an existing file relative
    to base_dir (species, graph, grammar, mesh and texture paths), so a content key changes when
    such a file changes."""
    found = {}

    def walk(v):
        if isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, str) and v.lower().endswith(_PATH_SUFFIXES) and len(v) < 4096:
            p = base_dir / v
            if p.is_file():
                found[v] = sha256_file(p)

    walk(scene)
    return dict(sorted(found.items()))


def content_key(scene, files: dict, outputs: dict) -> str:
    """sha256 of the canonical inputs of a variant and the Tendril version."""
    return hashlib.sha256(canonical({"scene": scene, "files": files, "outputs": outputs, "tendril": version()})).hexdigest()


# ---------------------------------------------------------------------------------------------
# The sweep

SWEEP_KEYS = {"tendril_sweep": True, "description": False, "seed": False, "base": True, "set": False,
              "parameters": False, "samples": False, "outputs": False, "name": False}


def expand(path, log=None) -> list:
    """The manifest entries (dicts) of the sweep file at `path`, in variant order."""
    path = Path(path)
    source = str(path)
    r = _Reader(source)
    doc = load_json(path, source)
    r.object(doc, "", SWEEP_KEYS)
    v = r.integer(doc["tendril_sweep"], "/tendril_sweep")
    if v != SWEEP_VERSION:
        raise r.fail("/tendril_sweep", f"this Tendril reads sweep format {SWEEP_VERSION}, got {v}")
    if "description" in doc:
        r.string(doc["description"], "/description", nonempty=False)
    name = r.string(doc.get("name", path.name.split(".")[0]), "/name")
    seed = r.integer(doc.get("seed", 0), "/seed", 0, 2**53)
    samples = r.integer(doc.get("samples", 1), "/samples", 1, MAX_VARIANTS)
    sweep_dir = path.resolve().parent
    scene, base_dir = _base_scene(r, doc["base"], "/base", sweep_dir)

    # Outputs: what each variant writes; lods and lod_ratio go into the scene's output.
    outputs_doc = r.object(doc.get("outputs", {}), "/outputs",
                           {"glb": False, "skeleton": False, "preview": False, "lods": False, "lod_ratio": False})
    outputs = {"glb": r.boolean(outputs_doc.get("glb", True), "/outputs/glb"),
               "skeleton": r.boolean(outputs_doc.get("skeleton", True), "/outputs/skeleton")}
    preview = outputs_doc.get("preview", PREVIEW_DEFAULT)
    if preview is False:
        outputs["preview"] = None
    else:
        r.object(preview, "/outputs/preview", {"width": True, "height": True})
        outputs["preview"] = {"width": r.integer(preview["width"], "/outputs/preview/width", 16, 4096),
                              "height": r.integer(preview["height"], "/outputs/preview/height", 16, 4096)}
    if not (outputs["glb"] or outputs["skeleton"] or outputs["preview"]):
        raise r.fail("/outputs", "asks for no output at all (glb, skeleton and preview are all off)")
    scene.setdefault("output", {})
    if not isinstance(scene["output"], dict):
        raise error(source, "/base", "the base scene's \"output\" is not an object")
    if "lods" in outputs_doc:
        scene["output"]["lods"] = r.integer(outputs_doc["lods"], "/outputs/lods", 1, 8)
    if "lod_ratio" in outputs_doc:
        scene["output"]["lod_ratio"] = r.number(outputs_doc["lod_ratio"], "/outputs/lod_ratio", 0.01, 1)

    # Fixed settings.
    fixed = r.object(doc.get("set", {}), "/set", {k: False for k in doc.get("set", {})} if isinstance(doc.get("set"), dict) else {})
    for pointer, value in fixed.items():
        where = f"/set/{escape_token(pointer)}"
        try:
            set_pointer(scene, pointer, copy.deepcopy(value))
        except ValueError as e:
            raise r.fail(where, f"cannot set {pointer} in the base scene: {e}") from None

    # Parameters.
    params = doc.get("parameters", [])
    if not isinstance(params, list):
        raise r.fail("/parameters", f"expected an array, got {_kind(params)} {_shown(params)}")
    grid, randoms, names = [], [], set()
    for i, p in enumerate(params):
        pp = f"/parameters/{i}"
        r.object(p, pp, {"pointer": True, "name": False, "values": False, "range": False, "random": False})
        pointer = r.string(p["pointer"], pp + "/pointer")
        try:
            split_pointer(pointer)
            set_pointer(copy.deepcopy(scene), pointer, 0)
        except ValueError as e:
            raise r.fail(pp + "/pointer", f"cannot vary {pointer} in the base scene: {e}") from None
        label = r.string(p.get("name", pointer), pp + "/name")
        if label in names:
            raise r.fail(pp + ("/name" if "name" in p else "/pointer"), f'a parameter named "{label}" is already varied')
        names.add(label)
        given = [k for k in ("values", "range", "random") if k in p]
        if len(given) != 1:
            raise r.fail(pp, 'expected exactly one of "values", "range" or "random"'
                         + (f" (got {', '.join(given)})" if given else ""))
        if "values" in p:
            values = p["values"]
            if not isinstance(values, list) or not values:
                raise r.fail(pp + "/values", f"expected a non-empty array, got {_kind(values)} {_shown(values)}")
            grid.append((label, pointer, values))
        elif "range" in p:
            grid.append((label, pointer, _range_values(r, p["range"], pp + "/range")))
        else:
            randoms.append((label, pointer, _random_spec(r, p["random"], pp + "/random")))

    total = samples * math.prod(len(g[2]) for g in grid)
    if total > MAX_VARIANTS:
        raise r.fail("/parameters", f"gives {total} variants, more than {MAX_VARIANTS}")

    entries, seen = [], {}
    combos = itertools.product(*[g[2] for g in grid]) if grid else [()]
    index = 0
    for combo in combos:
        for _ in range(samples):
            variant = copy.deepcopy(scene)
            values = {}
            for (label, pointer, _), value in zip(grid, combo):
                set_pointer(variant, pointer, copy.deepcopy(value))
                values[label] = value
            for label, pointer, spec in randoms:
                value = draw_random(seed, index, pointer, spec)
                set_pointer(variant, pointer, value)
                values[label] = value
            files = referenced_files(variant, base_dir)
            key = content_key(variant, files, outputs)
            entry = {"manifest": MANIFEST_VERSION, "index": index, "name": f"{name}-{index:05d}", "key": key,
                     "parameters": values, "scene": variant, "base_dir": str(base_dir), "files": files,
                     "outputs": outputs, "tendril": version(), "sweep": str(path.resolve())}
            index += 1
            if key in seen:
                if log:
                    log(f"{source}: variant {entry['index']} has the same inputs as variant {seen[key]}: kept once")
                continue
            seen[key] = entry["index"]
            entries.append(entry)
    return entries


def write_atomic(path: Path, data: bytes) -> None:
    """Writes data to path through a temporary file in the same directory and a rename."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            tmp.unlink()
        except OSError:
            pass
        raise


def write_manifest(entries: list, out_dir) -> Path:
    """<out_dir>/manifest.jsonl, one line per entry, written atomically."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = out / "manifest.jsonl"
    # Lines keep the sweep's order of parameters and the scene's of keys (readable); the content
    # key is over the canonical form.
    data = b"".join(json.dumps(e, separators=(",", ":"), ensure_ascii=False, allow_nan=False).encode() + b"\n"
                    for e in entries)
    write_atomic(target, data)
    return target

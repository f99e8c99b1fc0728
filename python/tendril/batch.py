"""Runs a manifest of plant variants, serially or as Dask tasks (docs/batch.md).

    python -m tendril.batch sweep SWEEP.json -o DIR        # what `tendril sweep` runs
    python -m tendril.batch batch DIR/manifest.jsonl ...   # what `tendril batch` runs

Each variant is one task, `run_variant(entry, out_dir)`: it grows the variant's scene through a
`tendril.Session`, writes its outputs and a `variant.json` into a temporary directory beside
`variants/` and renames that into place as `variants/<key>/`, so a variant directory is never
half-written and a variant whose directory exists and verifies is never written again. Only the
client (`run_batch`) writes the results file, one line per variant, and at the end the catalog
(`catalog.json`, `index.html`; tendril.catalog).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import struct
import sys
import time
import uuid
from pathlib import Path

from . import Error
from .sweep import MANIFEST_VERSION, error, sha256_file, write_atomic

VARIANT_FORMAT = "tendril-variant"
TMP_PREFIX = ".tmp-"
EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_FAILED = 0, 1, 2, 3


# ---------------------------------------------------------------------------------------------
# Manifest

ENTRY_KEYS = {"manifest": int, "index": int, "name": str, "key": str, "parameters": dict, "scene": dict,
              "base_dir": str, "files": dict, "outputs": dict, "tendril": str, "sweep": str}


def load_manifest(path) -> list:
    """The entries of a manifest file, checked line by line (errors name file:line)."""
    path = Path(path)
    source = str(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as e:
        raise error(source, "", f"cannot read: {e.strerror or e}") from None
    entries, keys = [], {}
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
        except json.JSONDecodeError as e:
            raise error(source, f"{n}:{e.colno}", f"syntax error: {e.msg}") from None
        if not isinstance(entry, dict):
            raise error(source, f"{n}", "expected an object per line")
        for k, kind in ENTRY_KEYS.items():
            if k not in entry:
                raise error(source, f"{n}", f'missing key "{k}"')
            if not isinstance(entry[k], kind) or isinstance(entry[k], bool):
                raise error(source, f"{n}:/{k}", f"expected {kind.__name__}")
        unknown = set(entry) - set(ENTRY_KEYS)
        if unknown:
            raise error(source, f"{n}", f'unknown key "{sorted(unknown)[0]}"')
        if entry["manifest"] != MANIFEST_VERSION:
            raise error(source, f"{n}:/manifest", f"this Tendril reads manifest version {MANIFEST_VERSION}, got {entry['manifest']}")
        if len(entry["key"]) != 64 or any(c not in "0123456789abcdef" for c in entry["key"]):
            raise error(source, f"{n}:/key", "expected 64 hex digits (a sha256)")
        if entry["key"] in keys:
            raise error(source, f"{n}:/key", f"the same variant as line {keys[entry['key']]}")
        keys[entry["key"]] = n
        entry["_line"] = n
        entries.append(entry)
    return entries


def parse_shard(text: str):
    """'i/N' -> (i, N) with 0 <= i < N."""
    try:
        i, n = (int(x) for x in text.split("/"))
    except ValueError:
        raise error("command line", "--shard", f'expected i/N such as 3/16, got "{text}"') from None
    if n < 1 or not 0 <= i < n:
        raise error("command line", "--shard", f"expected 0 <= i < N, got {text}")
    return i, n


# ---------------------------------------------------------------------------------------------
# Variant directories

def variants_dir(out_dir) -> Path:
    return Path(out_dir) / "variants"


def read_variant(vdir: Path, verify: bool = True):
    """The variant.json of a variant directory when it and every output it lists are intact
    (sizes and sha256), else None."""
    try:
        info = json.loads((vdir / "variant.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict) or info.get("format") != VARIANT_FORMAT or info.get("key") != vdir.name:
        return None
    outputs = info.get("outputs")
    if not isinstance(outputs, dict):
        return None
    if verify:
        for name, meta in outputs.items():
            f = vdir / name
            try:
                if f.stat().st_size != meta["bytes"] or sha256_file(f) != meta["sha256"]:
                    return None
            except (OSError, KeyError, TypeError):
                return None
    return info


def glb_triangles(path) -> list:
    """Triangles per level of detail in a .glb (summed over plants; nodes <plant>_LOD<k>)."""
    with open(path, "rb") as f:
        head = f.read(20)
        length, kind = struct.unpack_from("<II", head, 12)
        doc = json.loads(f.read(length))
    counts: dict = {}
    for node in doc.get("nodes", []):
        if "mesh" not in node:
            continue
        name = node.get("name", "")
        level = 0
        if "_LOD" in name and name.rsplit("_LOD", 1)[1].isdigit():
            level = int(name.rsplit("_LOD", 1)[1])
        tris = 0
        for prim in doc["meshes"][node["mesh"]]["primitives"]:
            if prim.get("mode", 4) != 4:
                continue
            if "indices" in prim:
                tris += doc["accessors"][prim["indices"]]["count"] // 3
            else:
                tris += doc["accessors"][prim["attributes"]["POSITION"]]["count"] // 3
        counts[level] = counts.get(level, 0) + tris
    return [counts[k] for k in sorted(counts)]


def _one_line(e: BaseException) -> str:
    text = str(e).strip().replace("\r", " ").replace("\n", " ")
    if isinstance(e, Error):
        return text
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


def _variant_source(entry: dict) -> str:
    return f"variant {entry['index']} ({entry['name']})"


def _variant_error(entry: dict, e: BaseException) -> str:
    """One line naming the variant: the Session's errors already do (it is their source)."""
    line = _one_line(e)
    return line if line.startswith(_variant_source(entry) + ":") else f"{_variant_source(entry)}: {line}"


def run_variant(entry: dict, out_dir: str, threads: int = 1) -> dict:
    """One variant, as a task: grows it and writes variants/<key>/ atomically. Returns its
    result record. A tendril.Error (bad parameters, a changed input file) is a failed record;
    any other exception propagates (so Dask retries the task)."""
    import tendril

    t0 = time.perf_counter()
    vroot = variants_dir(out_dir)
    final = vroot / entry["key"]
    record = {"key": entry["key"], "index": entry["index"], "name": entry["name"],
              "parameters": entry["parameters"], "worker": f"{socket.gethostname()}:{os.getpid()}"}
    existing = read_variant(final) if final.exists() else None
    if existing is not None:  # written by an earlier attempt whose result was lost (a killed worker)
        return _record_from(record, existing, "ok", reused=True)
    tendril.set_threads(threads)
    tmp = vroot / f"{TMP_PREFIX}{entry['key']}-{uuid.uuid4().hex[:12]}"
    vroot.mkdir(parents=True, exist_ok=True)
    tmp.mkdir()
    try:
        base_dir = Path(entry["base_dir"])
        for rel, digest in entry["files"].items():
            p = base_dir / rel
            if not p.is_file():
                raise error(str(p), "", "is gone since the sweep was expanded")
            if sha256_file(p) != digest:
                raise error(str(p), "", "changed since the sweep was expanded (its content key would differ): run `tendril sweep` again")
        timings = {}
        t = time.perf_counter()
        with _warnings_kept():
            s = tendril.Session(entry["scene"], base_dir=str(base_dir), source=_variant_source(entry))
            steps = s.run()
        timings["grow"] = time.perf_counter() - t
        outs = entry["outputs"]
        files = []
        t = time.perf_counter()
        if outs.get("glb"):
            s.export(str(tmp / "plant.glb"))
            files.append("plant.glb")
        if outs.get("skeleton"):
            s.export(str(tmp / "plant.skeleton.json"))
            files.append("plant.skeleton.json")
        timings["export"] = time.perf_counter() - t
        if outs.get("preview"):
            t = time.perf_counter()
            s.render(str(tmp / "preview.png"), outs["preview"]["width"], outs["preview"]["height"])
            files.append("preview.png")
            timings["render"] = time.perf_counter() - t
        if "plant.glb" in files:
            triangles = glb_triangles(tmp / "plant.glb")
        else:
            triangles = [sum(len(p.indices) for p in s.mesh().parts)]
        timings["total"] = time.perf_counter() - t0
        info = {
            "format": VARIANT_FORMAT, "version": 1, "key": entry["key"], "index": entry["index"],
            "name": entry["name"], "tendril": tendril.version(), "parameters": entry["parameters"],
            "scene": entry["scene"], "base_dir": entry["base_dir"], "files": entry["files"],
            "outputs": {f: {"sha256": sha256_file(tmp / f), "bytes": (tmp / f).stat().st_size} for f in files},
            "triangles": triangles, "steps": steps, "state_hash": f"{s.state_hash:016x}",
            "warnings": [str(w) for w in s.warnings], "growth_problems": [p.get("message", str(p)) for p in s.growth_problems()],
            "timings": {k: round(v, 4) for k, v in timings.items()},
        }
        write_atomic(tmp / "variant.json", json.dumps(info, indent=1).encode() + b"\n")
        _fsync_dir(tmp)
        try:
            os.rename(tmp, final)
        except OSError:
            # Another attempt got there first (a retried task whose first run was not dead after
            # all): keep its directory when it verifies, else replace it.
            other = read_variant(final)
            if other is not None:
                shutil.rmtree(tmp, ignore_errors=True)
                return _record_from(record, other, "ok", reused=True)
            shutil.rmtree(final, ignore_errors=True)
            os.rename(tmp, final)
        _fsync_dir(vroot)
        return _record_from(record, info, "ok")
    except Error as e:
        shutil.rmtree(tmp, ignore_errors=True)
        record.update(status="failed", error=_variant_error(entry, e),
                      timings={"total": round(time.perf_counter() - t0, 4)})
        return record
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


class _warnings_kept:
    """Tendril warnings stay in s.warnings (and variant.json); they are not printed per task."""

    def __enter__(self):
        import warnings

        self._cm = warnings.catch_warnings()
        self._cm.__enter__()
        import tendril

        warnings.simplefilter("ignore", tendril.TendrilWarning)

    def __exit__(self, *exc):
        return self._cm.__exit__(*exc)


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _record_from(record: dict, info: dict, status: str, reused: bool = False) -> dict:
    record.update(status=status, outputs=info["outputs"], triangles=info["triangles"], steps=info["steps"],
                  state_hash=info["state_hash"], timings=info["timings"])
    if reused:
        record["reused"] = True
    return record


def clean_temporaries(out_dir, keys) -> int:
    """Removes temporaries left by killed tasks of these variants; returns how many."""
    vroot = variants_dir(out_dir)
    if not vroot.is_dir():
        return 0
    keys = set(keys)
    n = 0
    for p in vroot.iterdir():
        if p.name.startswith(TMP_PREFIX) and p.name[len(TMP_PREFIX):len(TMP_PREFIX) + 64] in keys:
            shutil.rmtree(p, ignore_errors=True)
            n += 1
    return n


# ---------------------------------------------------------------------------------------------
# Progress

class Progress:
    """done / failed / skipped, variants per second and ETA on stderr: one updating line on a
    terminal, a line every `every` seconds otherwise."""

    def __init__(self, total: int, stream=None, quiet: bool = False, every: float = 10.0):
        self.total, self.stream, self.quiet, self.every = total, stream or sys.stderr, quiet, every
        self.done = self.failed = self.skipped = 0
        self.start = time.monotonic()
        self.last = self.start
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def restart(self):
        """Rates and ETA count from now (after a cluster has started)."""
        self.start = self.last = time.monotonic()

    def line(self) -> str:
        elapsed = time.monotonic() - self.start
        ran = self.done + self.failed
        rate = ran / elapsed if elapsed > 0 else 0.0
        left = self.total - ran - self.skipped
        eta = f"{left / rate:.0f} s" if rate > 0 and left > 0 else ("-" if left else "0 s")
        return (f"tendril batch: {ran + self.skipped}/{self.total}  done {self.done}  failed {self.failed}  "
                f"skipped {self.skipped}  {rate:.2f} variants/s  ETA {eta}")

    def update(self, status: str, force: bool = False):
        if status == "ok":
            self.done += 1
        elif status == "failed":
            self.failed += 1
        elif status == "skipped":
            self.skipped += 1
        if self.quiet:
            return
        now = time.monotonic()
        if self.tty:
            self.stream.write("\r\033[K" + self.line())
            self.stream.flush()
        elif force or now - self.last >= self.every:
            self.last = now
            self.stream.write(self.line() + "\n")
            self.stream.flush()

    def finish(self):
        if self.quiet:
            return
        self.stream.write(("\r\033[K" if self.tty else "") + self.line() + "\n")
        self.stream.flush()

    def say(self, text: str):
        if self.quiet:
            return
        self.stream.write(("\r\033[K" if self.tty else "") + text + "\n")
        self.stream.flush()


# ---------------------------------------------------------------------------------------------
# The batch

def results_name(shard) -> str:
    return "results.jsonl" if shard is None else f"results-{shard[0]}-of-{shard[1]}.jsonl"


def run_batch(manifest, out_dir=None, *, scheduler=None, workers=None, shard=None, local=False, retries=2,
              threads=0, client=None, quiet=False, stream=None, on_result=None, catalog=True) -> dict:
    """Runs the manifest's variants (those of the shard (i, N) when given) and returns a summary
    {"ok", "failed", "skipped", "results", "seconds"}. `client`: an existing dask Client to use;
    `on_result(record, client)` is called in the client after every result (tests use it)."""
    manifest = Path(manifest)
    entries = load_manifest(manifest)
    out = Path(out_dir) if out_dir else manifest.parent
    if shard is not None:
        entries = [e for e in entries if e["index"] % shard[1] == shard[0]]
    stream = stream or sys.stderr
    variants_dir(out).mkdir(parents=True, exist_ok=True)
    results_path = out / results_name(shard)
    progress = Progress(len(entries), stream, quiet)
    summary = {"ok": 0, "failed": 0, "skipped": 0, "results": str(results_path)}
    t_start = time.monotonic()

    with open(results_path, "a", encoding="utf-8") as results:
        def record(rec: dict, c=None):
            rec["time"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
            results.write(json.dumps(rec, separators=(",", ":"), ensure_ascii=False) + "\n")
            results.flush()
            summary[rec["status"] if rec["status"] != "ok" else "ok"] += 1
            if rec["status"] == "failed":
                progress.say(f"tendril batch: failed: {rec['error']}")
            progress.update(rec["status"])
            if on_result:
                on_result(rec, c)

        todo = []
        for e in entries:
            info = read_variant(variants_dir(out) / e["key"])
            if info is not None:
                rec = {"key": e["key"], "index": e["index"], "name": e["name"], "parameters": e["parameters"]}
                record(_record_from(rec, info, "skipped"))
            else:
                todo.append(e)

        if todo and local:
            for e in todo:
                try:
                    rec = run_variant(e, str(out), threads=threads)
                except Exception as ex:  # an unexpected failure of one variant: recorded, the batch goes on
                    rec = {"key": e["key"], "index": e["index"], "name": e["name"], "parameters": e["parameters"],
                           "status": "failed", "error": _variant_error(e, ex)}
                record(rec)
        elif todo:
            _run_dask(todo, out, scheduler, workers, retries, client, progress, record)
        clean_temporaries(out, [e["key"] for e in entries])
    progress.finish()
    summary["seconds"] = time.monotonic() - t_start
    if catalog:
        from .catalog import write_catalog

        cat = write_catalog(out)
        if not quiet:
            stream.write(f"tendril batch: {cat['count']} variants in {out / 'catalog.json'} and {out / 'index.html'}\n")
    return summary


def _run_dask(todo, out, scheduler, workers, retries, client, progress, record):
    try:
        from distributed import Client, as_completed
    except ImportError as e:
        raise error("tendril batch", "", f"Dask is not installed ({e}): install python3-distributed "
                                         "(scripts/setup), or run the variants in this process with --local") from None

    cluster = None
    own_client = client is None
    if client is None:
        if scheduler:
            client = Client(scheduler)
        else:
            n = workers or os.cpu_count() or 1
            t = time.monotonic()
            cluster = start_local_cluster(n, retries)
            client = Client(cluster)
            progress.say(f"tendril batch: local Dask cluster of {n} worker processes up in {time.monotonic() - t:.1f} s")
    try:
        link = getattr(client, "dashboard_link", None)
        if link and _has_dashboard(client):
            progress.say(f"tendril batch: Dask dashboard at {link}")
        progress.restart()
        futures = {}
        # Task keys name the variant (the dashboard groups them as "tendril-variant") and this run,
        # so a scheduler that still holds an earlier batch's result never hands it back instead.
        run = uuid.uuid4().hex[:8]
        for e in todo:
            f = client.submit(run_variant, e, str(out.resolve()), 1, key=f"tendril-variant-{e['index']}-{e['key'][:16]}-{run}",
                              retries=retries, pure=False)
            futures[f] = e
        for f in as_completed(list(futures)):
            e = futures[f]
            try:
                rec = f.result()
            except Exception as ex:  # retries exhausted (KilledWorker, an I/O error, ...)
                rec = {"key": e["key"], "index": e["index"], "name": e["name"], "parameters": e["parameters"],
                       "status": "failed", "error": _variant_error(e, ex)}
            record(rec, client)
            f.release()
    finally:
        if own_client:
            client.close()
        if cluster is not None:
            cluster.close()


def start_local_cluster(workers: int, retries: int = 2):
    """The LocalCluster `tendril batch` runs on: `workers` processes of one thread each.

    Each process renders with Mesa's llvmpipe on one thread (LP_NUM_THREADS=1, as Dask sets
    OMP_NUM_THREADS), so the processes share the cores instead of fighting over them, and keeps
    glibc's default trimming of freed memory: Dask's MALLOC_TRIM_THRESHOLD_=65536 returns every
    large buffer to the system and makes a preview render ~1.5x slower (bench/README.md). A
    value set in the environment wins for both. A killed worker's tasks are rescheduled up to
    `retries` times (the scheduler's allowed-failures)."""
    import dask
    from distributed import LocalCluster

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ["LP_NUM_THREADS"] = os.environ.get("LP_NUM_THREADS", "1")
    environ["MALLOC_TRIM_THRESHOLD_"] = os.environ.get("MALLOC_TRIM_THRESHOLD_", str(128 << 20))
    with dask.config.set({"distributed.scheduler.allowed-failures": max(retries, 0),
                          "distributed.nanny.pre-spawn-environ": environ}):
        # Any free port for the dashboard: two batches on one machine do not collide.
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")


def _bokeh_installed() -> bool:
    import importlib.util

    return importlib.util.find_spec("bokeh") is not None


def _has_dashboard(client) -> bool:
    """Whether the scheduler serves Dask's dashboard: it needs bokeh where the scheduler runs
    (Debian 12 has no python3-bokeh; pip's `bokeh<3` works with distributed 2022.12)."""
    try:
        return bool(client.run_on_scheduler(_bokeh_installed))
    except Exception:
        return False


# ---------------------------------------------------------------------------------------------
# Command line

def _sweep_main(args) -> int:
    from .sweep import expand, write_manifest

    def log(text):
        if not args.quiet:
            print(f"tendril sweep: {text}", file=sys.stderr)

    entries = expand(args.sweep, log=log)
    target = write_manifest(entries, args.output)
    if not args.quiet:
        print(f"tendril sweep: {len(entries)} variants in {target}", file=sys.stderr)
    return EXIT_OK


def _batch_main(args) -> int:
    shard = parse_shard(args.shard) if args.shard else None
    if args.workers is not None and args.workers < 1:
        raise error("command line", "--workers", f"must be >= 1, got {args.workers}")
    if args.retries < 0:
        raise error("command line", "--retries", f"must be >= 0, got {args.retries}")
    if args.local and (args.scheduler or args.workers):
        raise error("command line", "--local", "runs in this process: it takes neither --scheduler nor --workers")
    if args.scheduler and args.workers:
        raise error("command line", "--workers", "sizes the local cluster: it does not go with --scheduler")
    out = Path(args.output) if args.output else Path(args.manifest).parent
    if args.catalog_only:
        from .catalog import write_catalog

        cat = write_catalog(out)
        if not args.quiet:
            print(f"tendril batch: {cat['count']} variants in {out / 'catalog.json'} and {out / 'index.html'}", file=sys.stderr)
        return EXIT_OK
    if not Path(args.manifest).is_file():
        raise error(args.manifest, "", "no such manifest (make one with `tendril sweep SWEEP.json -o DIR`)")
    summary = run_batch(args.manifest, out, scheduler=args.scheduler, workers=args.workers, shard=shard,
                        local=args.local, retries=args.retries, threads=args.threads, quiet=args.quiet)
    if not args.quiet:
        print(f"tendril batch: {summary['ok']} ok, {summary['skipped']} skipped, {summary['failed']} failed in "
              f"{summary['seconds']:.1f} s; results in {summary['results']}", file=sys.stderr)
    return EXIT_FAILED if summary["failed"] else EXIT_OK


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        print(f"tendril: error: command line: {message} (see tendril {self.prog.split()[-1]} --help)", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)


def main(argv=None) -> int:
    parser = _Parser(prog="tendril", description="Plant libraries at scale (docs/batch.md).")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p = sub.add_parser("sweep", help="expand a sweep file into a manifest",
                       description="Expands a sweep file into DIR/manifest.jsonl: one line per variant with its "
                                   "resolved scene, parameters and content key.")
    p.add_argument("sweep", help="the sweep file (.json)")
    p.add_argument("-o", "--output", required=True, help="output directory (created if missing)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only errors")
    p = sub.add_parser("batch", help="run a manifest", formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Runs every variant of a manifest (on a local Dask cluster by default) into "
                                   "DIR/variants/<key>/, appends one line per variant to the results file and "
                                   "writes catalog.json and index.html.\nExit codes: 0 every variant ok or "
                                   "skipped, 3 some variants failed (see the results file), 2 bad input, 1 internal error.")
    p.add_argument("manifest", help="manifest.jsonl written by `tendril sweep`")
    p.add_argument("-o", "--output", help="library directory (default: the manifest's)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--workers", type=int, help="worker processes of the local Dask cluster (default: the cores)")
    p.add_argument("--shard", help="run only the variants whose index %% N == i (0 <= i < N)", metavar="i/N")
    p.add_argument("--local", action="store_true", help="run serially in this process, without Dask")
    p.add_argument("--retries", type=int, default=2, help="Dask retries of a task whose worker died or that raised (default 2)")
    p.add_argument("--threads", type=int, default=0, help="threads of a --local run (0 = all cores; Dask tasks use 1)")
    p.add_argument("--catalog-only", action="store_true", help="only rewrite catalog.json and index.html from variants/")
    p.add_argument("-q", "--quiet", action="store_true", help="print only errors")
    args = parser.parse_args(argv)
    try:
        return _sweep_main(args) if args.command == "sweep" else _batch_main(args)
    except Error as e:
        print(f"tendril: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("tendril: interrupted (finished variants are kept; run the batch again to resume)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""Throughput of `tendril batch` (docs/batch.md): a 200-variant ivy sweep run serially (--local)
and on a LocalCluster of 2 worker processes, the scaling efficiency, and the per-task overhead of
Dask (a trivial variant through Dask against in-process). Results go to bench/README.md.

    PYTHONPATH=build/ci/python /usr/bin/python3 bench/batch_bench.py [--variants 200] [--workers 2] [--json out.json]

The sweep is examples/sweeps/ivy-walls.json's (species x seeds x branch angles x a random light
tropism, 3 levels of detail, skeleton, preview), with as many seeds as it takes to reach
--variants and a 160 x 120 preview.
"""

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import tendril
from tendril import batch, sweep

ROOT = Path(__file__).resolve().parents[1]


def ivy_sweep(directory: Path, variants: int) -> Path:
    doc = json.loads((ROOT / "examples" / "sweeps" / "ivy-walls.json").read_text())
    doc["base"]["scene"] = str(ROOT / "examples" / "scenes" / "default.json")
    per_seed = 2 * 3  # species x branch angles
    seeds = -(-variants // per_seed)
    doc["parameters"][1]["range"] = {"from": 1, "to": seeds, "step": 1}
    doc["outputs"]["preview"] = {"width": 160, "height": 120}
    path = directory / "ivy-bench.json"
    path.write_text(json.dumps(doc))
    return path


def trivial_sweep(directory: Path, variants: int) -> Path:
    """Variants that do almost nothing: one plant, one step, only the skeleton."""
    (directory / "trivial-scene.json").write_text(json.dumps({
        "tendril": 1, "steps": 1,
        "environment": {"obstacles": [{"name": "ground", "type": "plane", "size": [2, 2]}]},
        "plants": [{"name": "ivy", "position": [0, 0, 0], "seed": 1}]}))
    doc = {"tendril_sweep": 1, "name": "trivial", "base": {"scene": "trivial-scene.json"},
           "parameters": [{"pointer": "/plants/0/seed", "range": {"from": 1, "to": variants, "step": 1}}],
           "outputs": {"glb": False, "skeleton": True, "preview": False}}
    path = directory / "trivial.json"
    path.write_text(json.dumps(doc))
    return path


def manifest_in(directory: Path, sweep_path: Path, name: str) -> Path:
    entries = sweep.expand(sweep_path)
    return sweep.write_manifest(entries, directory / name), len(entries)


def timed_local(manifest: Path) -> float:
    t = time.perf_counter()
    s = batch.run_batch(manifest, local=True, threads=1, quiet=True, catalog=False)
    assert s["failed"] == 0 and s["ok"] > 0, s
    return time.perf_counter() - t


def timed_dask(manifest: Path, client) -> float:
    t = time.perf_counter()
    s = batch.run_batch(manifest, client=client, quiet=True, catalog=False)
    assert s["failed"] == 0 and s["ok"] > 0, s
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variants", type=int, default=200)
    ap.add_argument("--trivial", type=int, default=200, help="trivial variants for the overhead")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", help="also write the figures here")
    args = ap.parse_args()

    # One thread per process, Mesa's llvmpipe included, for the serial run as for the workers
    # (which `tendril batch` starts with LP_NUM_THREADS=1).
    os.environ.setdefault("LP_NUM_THREADS", "1")
    from distributed import Client

    tmp = Path(tempfile.mkdtemp(prefix="tendril-batch-bench-"))
    try:
        ivy = ivy_sweep(tmp, args.variants)
        triv = trivial_sweep(tmp, args.trivial)
        fig = {"tendril": tendril.version(), "cores": os.cpu_count(), "workers": args.workers,
               "load_before": os.getloadavg()[0],
               "lp_num_threads": os.environ["LP_NUM_THREADS"]}

        m, n = manifest_in(tmp, ivy, "serial")
        fig["variants"] = n
        fig["serial_s"] = timed_local(m)
        print(f"serial (--local, 1 thread): {n} variants in {fig['serial_s']:.1f} s", file=sys.stderr)
        tasks = [json.loads(line) for line in (m.parent / "results.jsonl").read_text().splitlines()]
        fig["task_s_mean"] = sum(t["timings"]["total"] for t in tasks) / len(tasks)

        t = time.perf_counter()
        cluster = batch.start_local_cluster(args.workers)  # as `tendril batch` makes it
        client = Client(cluster)
        fig["cluster_start_s"] = time.perf_counter() - t
        try:
            m2, _ = manifest_in(tmp, ivy, "dask")
            fig["dask_s"] = timed_dask(m2, client)
            print(f"dask ({args.workers} workers): {n} variants in {fig['dask_s']:.1f} s "
                  f"(+ {fig['cluster_start_s']:.1f} s cluster start)", file=sys.stderr)
            same = all((m.parent / "variants" / d.name / "plant.glb").read_bytes() == (d / "plant.glb").read_bytes()
                       for d in (m2.parent / "variants").iterdir())
            fig["identical_outputs"] = same

            mt, nt = manifest_in(tmp, triv, "trivial-local")
            fig["trivial_variants"] = nt
            fig["trivial_local_s"] = timed_local(mt)
            mt2, _ = manifest_in(tmp, triv, "trivial-dask")
            fig["trivial_dask_s"] = timed_dask(mt2, client)
        finally:
            client.close()
            cluster.close()
        fig["load_after"] = os.getloadavg()[0]
        fig["serial_per_s"] = n / fig["serial_s"]
        fig["dask_per_s"] = n / fig["dask_s"]
        fig["speedup"] = fig["serial_s"] / fig["dask_s"]
        fig["efficiency"] = fig["speedup"] / args.workers
        fig["trivial_local_ms"] = 1000 * fig["trivial_local_s"] / nt
        # Dask runs `workers` tasks at once: its time per task on one worker is workers x wall / n.
        fig["trivial_dask_ms"] = 1000 * fig["trivial_dask_s"] * args.workers / nt
        fig["overhead_ms"] = fig["trivial_dask_ms"] - fig["trivial_local_ms"]
        print(json.dumps(fig, indent=1))
        print(f"""
| run | variants | wall time | variants/s |
|---|---|---|---|
| serial, `--local` (1 process, 1 thread) | {n} | {fig['serial_s']:.1f} s | {fig['serial_per_s']:.2f} |
| LocalCluster, {args.workers} worker processes | {n} | {fig['dask_s']:.1f} s (+ {fig['cluster_start_s']:.1f} s start) | {fig['dask_per_s']:.2f} |

speed-up {fig['speedup']:.2f}x, scaling efficiency {100 * fig['efficiency']:.0f} %; mean task {1000 * fig['task_s_mean']:.0f} ms;
trivial variant: {fig['trivial_local_ms']:.1f} ms in-process, {fig['trivial_dask_ms']:.1f} ms per task on a Dask worker
(overhead {fig['overhead_ms']:.1f} ms per task); outputs identical: {fig['identical_outputs']}""")
        if args.json:
            Path(args.json).write_text(json.dumps(fig, indent=1))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

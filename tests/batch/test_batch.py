"""Plant libraries on Dask (docs/batch.md): sweeps, manifests, batches on a LocalCluster of 2
worker processes against a serial run, shards, a killed worker, resumption, failing variants and
the `tendril sweep` / `tendril batch` commands. Run by ctest's `python_batch` test (PYTHONPATH holds
the module just built, TENDRIL_CLI the `tendril` binary). Variants are tiny (a few growth steps,
small previews) so the whole file runs in a couple of minutes on 2 cores."""

import hashlib
import json
import os
import shutil
import signal
import subprocess
from pathlib import Path

import pytest

import tendril
from tendril import batch, sweep

SOURCE = Path(os.environ.get("TENDRIL_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLI = os.environ.get("TENDRIL_CLI", str(SOURCE / "build" / "ci" / "tendril"))
OUTPUTS = ("plant.glb", "plant.skeleton.json", "preview.png")

TINY_SCENE = {
    "tendril": 1,
    "seed": 5,
    "steps": 18,
    "environment": {
        "obstacles": [
            {"name": "ground", "type": "plane", "size": [3, 3]},
            {"name": "wall", "type": "wall", "size": [1.2, 1.0, 0.1]},
        ],
        "lights": [{"type": "directional", "direction": [-0.1, -1, -0.5]}],
    },
    "plants": [{"name": "ivy", "species": "japanese-ivy", "position": [0.0, 0.0, 0.08], "seed": 1}],
    "output": {"radial_segments": 5, "subdivisions": 1},
}


def tiny_sweep(seeds=5, samples=4, **extra):
    """2 species x `seeds` seeds x `samples` random light tropisms (40 variants by default)."""
    doc = {
        "tendril_sweep": 1,
        "name": "tiny",
        "seed": 11,
        "base": {"scene": "scene.json"},
        "samples": samples,
        "parameters": [
            {"name": "species", "pointer": "/plants/0/species", "values": ["japanese-ivy", "clematis"]},
            {"name": "seed", "pointer": "/plants/0/seed", "range": {"from": 1, "to": seeds, "step": 1}},
            {"name": "light", "pointer": "/plants/0/species/tropisms/light", "random": {"min": 0.02, "max": 0.3}},
        ],
        "outputs": {"glb": True, "lods": 2, "skeleton": True, "preview": {"width": 48, "height": 36}},
    }
    doc.update(extra)
    return doc


def write_sweep(directory: Path, doc, name="sweep.json") -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "scene.json").write_text(json.dumps(TINY_SCENE))
    path = directory / name
    path.write_text(json.dumps(doc, indent=1))
    return path


def sha(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def library_hashes(out: Path) -> dict:
    """{key: {output: sha256}} of every variant directory, hashed from the files themselves."""
    found = {}
    for d in sorted((out / "variants").iterdir()):
        assert not d.name.startswith("."), f"a temporary was left behind: {d}"
        assert sorted(p.name for p in d.iterdir()) == sorted(OUTPUTS + ("variant.json",)), d
        found[d.name] = {f: sha(d / f) for f in OUTPUTS}
    return found


def results(path: Path) -> list:
    return [json.loads(line) for line in path.read_text().splitlines()]


def expanded(tmp: Path, doc) -> Path:
    """A fresh library directory holding the manifest of `doc`."""
    path = write_sweep(tmp / "sweep", doc)
    entries = sweep.expand(path)
    return sweep.write_manifest(entries, tmp / "lib")


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The 40-variant sweep run serially in this process (--local): the reference."""
    tmp = tmp_path_factory.mktemp("serial")
    manifest = expanded(tmp, tiny_sweep())
    summary = batch.run_batch(manifest, local=True, quiet=True)
    assert summary["ok"] == 40 and summary["failed"] == 0 and summary["skipped"] == 0
    return manifest, library_hashes(manifest.parent)


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster of 2 worker processes, 1 thread each (as `tendril batch` makes one)."""
    from distributed import Client

    c = batch.start_local_cluster(2, retries=3)
    client = Client(c)
    yield client
    client.close()
    c.close()


def copy_manifest(manifest: Path, tmp: Path) -> Path:
    (tmp / "lib").mkdir(parents=True)
    return Path(shutil.copy(manifest, tmp / "lib" / "manifest.jsonl"))


def test_manifest_lines(serial):
    manifest, hashes = serial
    entries = batch.load_manifest(manifest)
    assert [e["index"] for e in entries] == list(range(40))
    assert len({e["key"] for e in entries}) == 40 and set(hashes) == {e["key"] for e in entries}
    e = entries[0]
    assert e["parameters"]["species"] == "japanese-ivy" and e["parameters"]["seed"] == 1
    # The species given by name became {"base": name} to take the varied tropism.
    assert e["scene"]["plants"][0]["species"] == {"base": "japanese-ivy", "tropisms": {"light": e["parameters"]["light"]}}
    assert e["scene"]["output"]["lods"] == 2 and Path(e["base_dir"]).is_absolute()
    # The key is the sha256 of the canonical inputs and the version.
    assert e["key"] == sweep.content_key(e["scene"], e["files"], e["outputs"])
    assert e["tendril"] == tendril.version()
    lights = [x["parameters"]["light"] for x in entries]
    assert all(0.02 <= x <= 0.3 for x in lights) and len(set(lights)) == 40


def test_variant_json_and_catalog(serial):
    manifest, hashes = serial
    out = manifest.parent
    key = next(iter(hashes))
    info = json.loads((out / "variants" / key / "variant.json").read_text())
    assert info["key"] == key and info["steps"] == 18
    assert {f: m["sha256"] for f, m in info["outputs"].items()} == hashes[key]
    assert len(info["triangles"]) == 2 and info["triangles"][0] > info["triangles"][1] > 0
    assert set(info["timings"]) >= {"grow", "export", "render", "total"}
    catalog = json.loads((out / "catalog.json").read_text())
    assert catalog["format"] == "tendril-catalog" and catalog["count"] == 40
    assert {v["key"] for v in catalog["variants"]} == set(hashes)
    page = (out / "index.html").read_text()
    assert page.count('<div class="card">') == 40 and f"variants/{key}/preview.png" in page
    assert "clematis" in page and "plant.glb" in page


def test_local_cluster_matches_serial(serial, cluster, tmp_path):
    manifest, reference = serial
    mine = copy_manifest(manifest, tmp_path)
    summary = batch.run_batch(mine, client=cluster, quiet=True)
    assert summary["ok"] == 40 and summary["failed"] == 0
    assert library_hashes(mine.parent) == reference
    recs = results(mine.parent / "results.jsonl")
    assert sorted(r["key"] for r in recs) == sorted(reference)
    workers = {r["worker"] for r in recs}
    assert len(workers) == 2 and not any(w.endswith(f":{os.getpid()}") for w in workers)


def test_shards_cover_the_manifest(serial, tmp_path):
    manifest, reference = serial
    mine = copy_manifest(manifest, tmp_path)
    seen = []
    for i in range(3):
        summary = batch.run_batch(mine, shard=(i, 3), local=True, quiet=True)
        recs = results(mine.parent / f"results-{i}-of-3.jsonl")
        assert {r["index"] % 3 for r in recs} == {i} and summary["ok"] == len(recs)
        seen += [r["key"] for r in recs]
    assert sorted(seen) == sorted(reference)
    assert library_hashes(mine.parent) == reference
    assert not (mine.parent / "results.jsonl").exists()


def test_killed_worker_loses_nothing(serial, cluster, tmp_path):
    manifest, reference = serial
    mine = copy_manifest(manifest, tmp_path)
    killed = []

    def kill_one(record, client):
        if len(killed) == 0 and record["index"] >= 0 and len(results(mine.parent / "results.jsonl")) >= 4:
            pids = client.run(os.getpid)
            busy = [w for w, tasks in client.processing().items() if tasks]
            victim = busy[0] if busy else sorted(pids)[0]
            os.kill(pids[victim], signal.SIGKILL)
            killed.append(pids[victim])

    before = set(cluster.run(os.getpid).values())
    summary = batch.run_batch(mine, client=cluster, quiet=True, on_result=kill_one)
    assert killed and killed[0] in before
    assert summary["ok"] == 40 and summary["failed"] == 0
    # No variant lost, none written twice or half, no temporaries left.
    assert library_hashes(mine.parent) == reference
    recs = results(mine.parent / "results.jsonl")
    keys = [r["key"] for r in recs]
    assert len(keys) == 40 and sorted(keys) == sorted(reference)
    # The nanny replaced the killed process.
    cluster.wait_for_workers(2)
    after = set(cluster.run(os.getpid).values())
    assert killed[0] not in after


def test_resume_runs_only_missing_variants(serial, tmp_path):
    manifest, reference = serial
    lib = tmp_path / "lib"
    shutil.copytree(manifest.parent, lib)
    (lib / "results.jsonl").unlink()
    keys = sorted(reference)
    removed = keys[:3]
    for k in removed:
        shutil.rmtree(lib / "variants" / k)
    # A damaged output does not verify: that variant runs again.
    damaged = keys[5]
    png = lib / "variants" / damaged / "preview.png"
    png.write_bytes(png.read_bytes()[:100])
    # A killed task's temporary and a half-made directory without variant.json.
    (lib / "variants" / f".tmp-{keys[7]}-deadbeef").mkdir()
    (lib / "variants" / f".tmp-{keys[7]}-deadbeef" / "plant.glb").write_bytes(b"glTF")
    shutil.rmtree(lib / "variants" / keys[9])
    (lib / "variants" / keys[9]).mkdir()
    (lib / "variants" / keys[9] / "plant.glb").write_bytes(b"half")
    summary = batch.run_batch(lib / "manifest.jsonl", local=True, quiet=True)
    recs = results(lib / "results.jsonl")
    ran = sorted(r["key"] for r in recs if r["status"] == "ok")
    assert ran == sorted(removed + [damaged, keys[9]])
    assert summary["skipped"] == 40 - len(ran) and summary["ok"] == len(ran)
    assert library_hashes(lib) == reference
    # Everything verifies now: a third run skips all.
    summary = batch.run_batch(lib / "manifest.jsonl", local=True, quiet=True)
    assert summary["skipped"] == 40 and summary["ok"] == 0


def test_a_retried_task_does_not_write_twice(serial, tmp_path):
    """A task run again after its first attempt finished (its worker died before reporting) finds
    the directory and leaves it as it is; one that finds a broken directory replaces it whole."""
    manifest, reference = serial
    entry = batch.load_manifest(manifest)[3]
    out = tmp_path / "lib"
    first = batch.run_variant(entry, str(out))
    vdir = out / "variants" / entry["key"]
    stamp = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in vdir.iterdir()}
    again = batch.run_variant(entry, str(out))
    assert again["reused"] and again["outputs"] == first["outputs"] and "reused" not in first
    assert {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in vdir.iterdir()} == stamp
    (vdir / "variant.json").unlink()  # a directory a crash left without its variant.json
    third = batch.run_variant(entry, str(out))
    assert "reused" not in third and {f: m["sha256"] for f, m in third["outputs"].items()} == reference[entry["key"]]
    assert sorted(p.name for p in (out / "variants").iterdir()) == [entry["key"]]


def test_bad_parameter_fails_alone(tmp_path, cluster):
    doc = tiny_sweep(seeds=1, samples=1)
    doc["parameters"] = [{"name": "segment", "pointer": "/plants/0/species/segment_length", "values": [0.04, "long", 0.05]}]
    manifest = expanded(tmp_path, doc)
    summary = batch.run_batch(manifest, client=cluster, quiet=True)
    assert summary["ok"] == 2 and summary["failed"] == 1
    recs = {r["index"]: r for r in results(manifest.parent / "results.jsonl")}
    bad = recs[1]
    assert bad["status"] == "failed" and "\n" not in bad["error"]
    assert bad["error"].startswith("variant 1 (tiny-00001):/plants/0/species/segment_length: expected a number")
    assert recs[0]["status"] == recs[2]["status"] == "ok"
    assert sorted(p.name for p in (manifest.parent / "variants").iterdir()) == sorted([recs[0]["key"], recs[2]["key"]])
    # A re-run skips the good ones and fails the bad one again.
    summary = batch.run_batch(manifest, local=True, quiet=True)
    assert (summary["ok"], summary["skipped"], summary["failed"]) == (0, 2, 1)


def test_changed_input_file_changes_the_key(tmp_path):
    species = json.loads((SOURCE / "examples" / "species" / "japanese-ivy.json").read_text())
    d = tmp_path / "sweep"
    d.mkdir()
    (d / "my-ivy.json").write_text(json.dumps(species))
    doc = tiny_sweep(seeds=2, samples=1)
    doc["parameters"] = doc["parameters"][1:2]
    doc["set"] = {"/plants/0/species": "my-ivy.json"}
    path = write_sweep(d, doc)
    first = sweep.expand(path)
    assert first[0]["files"] == {"my-ivy.json": sha(d / "my-ivy.json")}
    assert [e["key"] for e in sweep.expand(path)] == [e["key"] for e in first]  # reproducible
    sweep.write_manifest(first, tmp_path / "lib")
    species["segment_length"] = 0.05
    (d / "my-ivy.json").write_text(json.dumps(species))
    second = sweep.expand(path)
    assert all(a["key"] != b["key"] for a, b in zip(first, second))
    # The old manifest no longer matches its file: its variants fail, naming the file.
    summary = batch.run_batch(tmp_path / "lib" / "manifest.jsonl", local=True, quiet=True)
    assert summary["failed"] == 2
    err = results(tmp_path / "lib" / "results.jsonl")[0]["error"]
    assert "my-ivy.json" in err and "changed since the sweep was expanded" in err


def test_random_draws_follow_the_sweep_seed(tmp_path):
    a = sweep.expand(write_sweep(tmp_path / "a", tiny_sweep(seeds=2, samples=2)))
    b = sweep.expand(write_sweep(tmp_path / "b", tiny_sweep(seeds=2, samples=2)))
    c = sweep.expand(write_sweep(tmp_path / "c", tiny_sweep(seeds=2, samples=2, seed=12)))
    light = lambda es: [e["parameters"]["light"] for e in es]  # noqa: E731
    assert light(a) == light(b) and light(a) != light(c)
    assert len(a) == 8


def test_ranges_and_counts(tmp_path):
    doc = tiny_sweep()
    doc["samples"] = 1
    doc["parameters"] = [
        {"pointer": "/steps", "range": {"from": 10, "to": 20, "count": 3}},
        {"pointer": "/plants/0/species/segment_length", "range": {"from": 0.03, "to": 0.05, "step": 0.01}},
    ]
    es = sweep.expand(write_sweep(tmp_path, doc))
    assert [(e["parameters"]["/steps"], e["parameters"]["/plants/0/species/segment_length"]) for e in es] == [
        (s, x) for s in (10, 15, 20) for x in (0.03, 0.04, 0.05)]


@pytest.mark.parametrize("change, where, message", [
    (lambda d: d.update(tendril_sweep=2), "/tendril_sweep", "this Tendril reads sweep format 1, got 2"),
    (lambda d: d.update(sead=3), "/sead", 'unknown key "sead" (did you mean "seed"?)'),
    (lambda d: d["parameters"][1]["range"].update(step=0), "/parameters/1/range/step", "must be > 0, got 0"),
    (lambda d: d["parameters"][1]["range"].update(to=0), "/parameters/1/range/to", 'must not be below "from" (1), got 0'),
    (lambda d: d["parameters"][0].update(values=[]), "/parameters/0/values", "expected a non-empty array, got array []"),
    (lambda d: d["parameters"][2]["random"].update(min="low"), "/parameters/2/random/min", 'expected a number, got string "low"'),
    (lambda d: d["parameters"][0].update(pointer="/plants/3/seed"), "/parameters/0/pointer",
     "cannot vary /plants/3/seed in the base scene: /plants has 1 element, no index 3"),
    (lambda d: d["parameters"][0].update(pointer="plants"), "/parameters/0/pointer", "cannot vary plants in the base scene: a JSON pointer starts with \"/\""),
    (lambda d: d["outputs"]["preview"].update(width=8), "/outputs/preview/width", "must be in [16, 4096], got 8"),
    (lambda d: d.update(base={"scene": "scene.json", "grammar": "algae"}), "/base",
     'expected exactly one of "scene", "graph" or "grammar" (got scene, grammar)'),
    (lambda d: d["parameters"][0].update(range={"from": 1, "to": 2, "step": 1}), "/parameters/0",
     'expected exactly one of "values", "range" or "random" (got values, range)'),
])
def test_sweep_errors_are_one_line(tmp_path, change, where, message):
    doc = tiny_sweep()
    change(doc)
    path = write_sweep(tmp_path, doc)
    with pytest.raises(tendril.Error) as e:
        sweep.expand(path)
    assert str(e.value) == f"{path}:{where}: {message}"
    assert e.value.location == where


def test_sweep_syntax_error_names_line_and_column(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"tendril_sweep": 1,\n  "seed": 3,,\n}')
    with pytest.raises(tendril.Error, match=r"broken\.json:2:13: syntax error"):
        sweep.expand(path)


def test_graph_and_grammar_bases(tmp_path):
    for base, model in (({"graph": "fig2"}, "graph"), ({"grammar": "algae"}, "lsystem")):
        doc = {"tendril_sweep": 1, "base": base, "set": {"/steps": 3},
               "parameters": [{"pointer": "/plants/0/seed", "values": [1, 2]}],
               "outputs": {"preview": False}}
        path = tmp_path / f"{model}.json"
        path.write_text(json.dumps(doc))
        es = sweep.expand(path)
        assert [e["scene"]["plants"][0]["model"] for e in es] == [model, model]
        sweep.write_manifest(es, tmp_path / model)
        summary = batch.run_batch(tmp_path / model / "manifest.jsonl", local=True, quiet=True, catalog=False)
        assert summary["ok"] == 2, results(tmp_path / model / "results.jsonl")


def run_cli(*args, cwd=None):
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_cli_sweep_and_batch(tmp_path):
    path = write_sweep(tmp_path / "s", tiny_sweep(seeds=2, samples=1))
    lib = tmp_path / "lib"
    p = run_cli("sweep", path, "-o", lib)
    assert p.returncode == 0, p.stderr
    assert "4 variants" in p.stderr and len((lib / "manifest.jsonl").read_text().splitlines()) == 4
    # On a local Dask cluster of 2 worker processes.
    p = run_cli("batch", lib / "manifest.jsonl", "--workers", "2")
    assert p.returncode == 0, p.stderr
    assert "4 ok, 0 skipped, 0 failed" in p.stderr
    assert json.loads((lib / "catalog.json").read_text())["count"] == 4
    # Again: everything is there and verifies.
    p = run_cli("batch", lib / "manifest.jsonl", "--local")
    assert p.returncode == 0 and "0 ok, 4 skipped, 0 failed" in p.stderr, p.stderr
    assert len(results(lib / "results.jsonl")) == 8
    # Bad arguments and files: exit code 2, one line.
    for args, line in ((("batch", lib / "manifest.jsonl", "--shard", "5/2"),
                        "tendril: error: command line:--shard: expected 0 <= i < N, got 5/2"),
                       (("batch", tmp_path / "none.jsonl", "--local"),
                        f"tendril: error: {tmp_path / 'none.jsonl'}: no such manifest (make one with `tendril sweep SWEEP.json -o DIR`)")):
        p = run_cli(*args)
        assert p.returncode == 2 and p.stderr == line + "\n", p.stderr
    bad = tiny_sweep()
    bad["outputs"]["lods"] = 9
    p = run_cli("sweep", write_sweep(tmp_path / "bad", bad), "-o", tmp_path / "badlib")
    assert p.returncode == 2
    assert p.stderr == f"tendril: error: {tmp_path / 'bad' / 'sweep.json'}:/outputs/lods: must be in [1, 8], got 9\n"
    assert not (tmp_path / "badlib").exists()


def test_cli_failed_variant_exit_code(tmp_path):
    doc = tiny_sweep(seeds=1, samples=1)
    doc["parameters"] = [{"pointer": "/plants/0/species/segment_length", "values": [0.04, -3]}]
    lib = tmp_path / "lib"
    assert run_cli("sweep", write_sweep(tmp_path / "s", doc), "-o", lib).returncode == 0
    p = run_cli("batch", lib / "manifest.jsonl", "--local")
    assert p.returncode == 3, p.stderr
    assert "tendril batch: failed: variant 1 (tiny-00001):/plants/0/species/segment_length: " in p.stderr

"""The Python module against the CLI and against itself (run by ctest's `python` test:
PYTHONPATH holds the module just built, TENDRIL_CLI the `tendril` binary)."""

import hashlib
import json
import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

import tendril

SOURCE = Path(os.environ.get("TENDRIL_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLI = os.environ.get("TENDRIL_CLI", str(SOURCE / "build" / "ci" / "tendril"))
SCENES = SOURCE / "examples" / "scenes"


def sha(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def wall_scene(steps=40, model="climb", species="japanese-ivy", seed=3):
    """Ivy at the foot of a wall made of arrays (a box of 8 vertices), on a ground plane."""
    w, h, d = 1.2, 1.0, 0.1
    v = np.array([[x, y, z] for x in (-w / 2, w / 2) for y in (0.0, h) for z in (-d / 2, d / 2)], dtype=np.float32)
    # Outward-facing triangles of the box (vertex index = 4 x + 2 y + z).
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = np.array([t for a, b, c, dd in quads for t in ((a, b, c), (a, c, dd))], dtype=np.int64)
    return {
        "tendril": 1,
        "seed": seed,
        "steps": steps,
        "environment": {
            "obstacles": [
                {"name": "ground", "type": "plane", "size": [4, 4]},
                tendril.mesh_obstacle(v, tris, name="wall"),
            ],
            "lights": [{"type": "directional", "direction": [-0.1, -1, -0.5]}],
        },
        "plants": [{"name": "ivy", "model": model, "species": species, "position": [0.0, 0.0, d / 2 + 0.02], "seed": 1}],
    }


def test_default_scene_grows_what_the_cli_grows(tmp_path):
    cli_out = tmp_path / "cli"
    subprocess.run([CLI, "grow", str(SCENES / "default.json"), "-o", str(cli_out), "--format", "glb,skeleton",
                    "--quiet"], check=True)
    s = tendril.Session.open(str(SCENES / "default.json"))
    steps = s.run()
    assert steps > 0 and s.segment_count > 1000
    s.export(str(tmp_path / "py.glb"))
    assert sha(tmp_path / "py.glb") == sha(cli_out / "plant.glb")
    # The plant graph (docs/skeleton-format.md), named by its extension.
    s.export(str(tmp_path / "py.skeleton.json"))
    assert sha(tmp_path / "py.skeleton.json") == sha(cli_out / "plant.skeleton.json")
    skeleton = json.loads((tmp_path / "py.skeleton.json").read_text())
    assert skeleton["format"] == "tendril-skeleton" and skeleton["version"] == 1
    assert [len(p["nodes"]) for p in skeleton["plants"]] == [s.plant(i).positions.shape[0] for i in range(2)]


def test_results_do_not_depend_on_the_thread_count():
    hashes = []
    for n in (1, 2, 0):
        tendril.set_threads(n)
        s = tendril.Session(wall_scene(steps=30, model="particles", species="ivy-particles"))
        s.run()
        hashes.append(s.state_hash)
    tendril.set_threads(0)
    assert hashes[0] == hashes[1] == hashes[2]


def test_a_session_round_trips(tmp_path):
    s = tendril.Session(wall_scene(steps=60), base_dir=str(tmp_path))
    s.step(20)
    s.edit({"edit": "paint_stroke", "kind": "attract", "radius": 0.3, "points": [[0.3, 0.8, 0.1]]})
    s.step(5)
    s.save(str(tmp_path / "s.tses"))
    t = tendril.Session.open(str(tmp_path / "s.tses"))
    assert t.state_hash == s.state_hash
    assert t.step_count == s.step_count == 25
    assert t.journal() == s.journal()
    s.step(15)
    t.step(15)
    assert t.state_hash == s.state_hash
    # save_state / load_state: back to an earlier state exactly.
    state = s.save_state()
    before = s.state_hash
    s.step(5)
    assert s.state_hash != before
    s.load_state(state)
    assert s.state_hash == before


def test_a_bad_species_dict_names_its_place():
    s = tendril.Session(wall_scene())
    with pytest.raises(tendril.Error) as e:
        s.add_plant({"name": "bad", "model": "particles", "position": [1.0, 0.0, 0.5],
                     "species": {"model": "particles", "growth_rate": "fast"}})
    msg = str(e.value)
    assert "\n" not in msg
    assert "/species/growth_rate" in msg, msg
    assert e.value.location == "/plants/1/species/growth_rate" and e.value.source == "<python>"
    # Scenes: the pointer of the bad key inside the scene document.
    scene = wall_scene()
    scene["plants"][0]["sed"] = 1
    with pytest.raises(tendril.Error, match=r"/plants/0/sed: unknown key \"sed\""):
        tendril.Session(scene)
    scene = wall_scene()
    scene["environment"]["obstacles"][1]["triangles"][4] = 99
    with pytest.raises(tendril.Error, match=r"/environment/obstacles/1/triangles/4: must be a vertex index in \[0, 7\]"):
        tendril.Session(scene)
    with pytest.raises(tendril.Error, match=r"vertices: expected an array of shape \(n, 3\)"):
        tendril.mesh_obstacle(np.zeros((4, 2)), [[0, 1, 2]])
    with pytest.raises(tendril.Error, match=r"/edit: must be one of"):
        s.edit({"edit": "prune"})
    with pytest.raises(tendril.Error, match="nothing to undo"):
        s.undo()
    with pytest.raises(tendril.Error, match="no-such.json"):
        tendril.Session.open("no-such.json")
    with pytest.raises(tendril.Error):
        tendril.Session({"tendril": 1, "plants": [{"position": [0, 0, 0]}], "environment": {"obstacles": [set()]}})


def test_arrays_are_views_of_the_snapshot():
    s = tendril.Session(wall_scene(steps=30))
    s.run()
    p = s.plant(0)
    assert p.node_count > 10 and p.leaf_count > 0
    a, b = p.positions, p.positions
    assert np.shares_memory(a, b), "two reads of one snapshot are one buffer"
    assert a.base is not None and not a.flags.owndata and not a.flags.writeable
    assert a.dtype == np.float32 and a.shape == (p.node_count, 3)
    assert p.orientations.shape == (p.node_count, 4)
    assert np.allclose(np.linalg.norm(p.orientations, axis=1), 1.0, atol=1e-4)
    assert p.parents[0] == -1 and (p.parents[1:] < np.arange(1, p.node_count)).all()
    assert np.allclose(p.tips(), p.positions + p.lengths[:, None] * direction(p.orientations), atol=1e-5)
    del p  # the view keeps the snapshot alive
    assert np.isfinite(a).all()
    model = s.mesh()
    parts = model.parts
    assert [pt.name for pt in parts][:1] == ["bark"]
    for pt in parts:
        assert np.shares_memory(pt.positions, pt.positions) and not pt.positions.flags.writeable
        assert pt.indices.dtype == np.uint32 and pt.indices.max() < len(pt.positions)
        assert pt.normals.shape == pt.positions.shape and pt.uvs.shape == (len(pt.positions), 2)
    kinds = {m["kind"] for m in model.materials}
    assert {"bark", "leaf"} <= kinds
    leaf = next(m for m in model.materials if m["kind"] == "leaf")
    assert leaf["alpha_mask"] and model.images[leaf["image"]]["data"][:4] == b"\x89PNG"


def direction(q):
    """+y of each quaternion (x, y, z, w)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)], axis=1)


def test_ivy_climbs_a_wall_made_of_arrays():
    s = tendril.Session(wall_scene(steps=120))
    s.run()
    p = s.plant(0)
    top = p.tips()[:, 1].max()
    assert top > 0.3, f"the ivy climbed only to {top:.2f} m"
    # Nothing of it inside the wall (|x| < 0.6, 0 < y < 1, |z| < 0.05).
    inside = (np.abs(p.positions[:, 0]) < 0.6 - 1e-3) & (p.positions[:, 1] > 1e-3) & \
             (p.positions[:, 1] < 1 - 1e-3) & (np.abs(p.positions[:, 2]) < 0.05 - 1e-4)
    assert not inside.any()


def test_edits_undo_and_redo():
    s = tendril.Session(wall_scene(steps=60, model="particles", species="ivy-particles"))
    s.step(30)
    before = s.state_hash
    nodes = s.plant(0).node_count
    s.edit({"edit": "cut", "plant": 0, "node": nodes // 2})
    assert s.can_undo
    cut = s.state_hash
    assert cut != before
    s.undo()
    assert s.state_hash == before and s.can_redo
    s.redo()
    assert s.state_hash == cut
    j = s.journal()
    assert j["tendril_edits"] == 1 and [e["edit"] for e in j["edits"]] == ["step", "cut", "undo", "redo"]
    # The journal replays to the same state.
    t = tendril.Session(wall_scene(steps=60, model="particles", species="ivy-particles"))
    t.run_script(j)
    assert t.state_hash == s.state_hash


def test_every_model_from_python():
    s = tendril.Session(wall_scene(steps=20))
    assert set(tendril.models()) == {"climb", "particles", "lsystem", "graph"}
    assert "japanese-ivy" in tendril.presets("climb")
    assert "ivy-particles" in tendril.presets("particles")
    grammars = tendril.presets("lsystem")
    assert grammars
    graphs = tendril.presets("graph")
    assert any(g.endswith("sunflower.json") for g in graphs)
    with pytest.raises(tendril.Error, match="model: must be one of"):
        tendril.presets("tree")
    i = s.add_plant({"name": "lychnis", "model": "lsystem", "grammar": "abop-ch3-lychnis", "position": [1.5, 0, 1]})
    g = s.add_plant({"name": "sunflower", "model": "graph", "graph": next(x for x in graphs if x.endswith("sunflower.json")),
                     "position": [-1.5, 0, 1]})
    s.run(20)
    assert s.plant(i).model == "lsystem" and s.plant(i).node_count > 1
    assert s.plant(g).model == "graph" and s.plant(g).node_count > 1
    names = [name for name, _ in s.mesh().objects]
    assert names == ["ivy", "lychnis", "sunflower"]
    # The grammar and the graph themselves rather than their files.
    text = (SOURCE / "examples" / "grammars" / "abop-1.24a.ls").read_text()
    k = s.add_plant({"name": "text", "model": "lsystem", "grammar_text": text, "position": [2.0, 0, 1]})
    graph = json.loads((SOURCE / "examples" / "graphs" / "sunflower.json").read_text())
    d = s.add_plant({"name": "doc", "model": "graph", "graph": str(SOURCE / "examples" / "graphs" / "sunflower.json"),
                     "graph_document": graph, "position": [-2.0, 0, 1]})
    s.run(5)
    assert s.plant(k).node_count > 1 and s.plant(d).node_count == s.plant(g).node_count
    with pytest.raises(tendril.Error, match=r"line:? ?\d|\d+:\d+"):
        s.add_plant({"name": "bad", "model": "lsystem", "grammar_text": "axiom: F(\n", "position": [2.5, 0, 1]})


def test_obstacles_from_files(tmp_path):
    s = tendril.Session(wall_scene(steps=10))
    (tmp_path / "tri.obj").write_text("v 2 0 2\nv 3 0 2\nv 2 1 2\nf 1 2 3\n")
    with pytest.warns(tendril.TendrilWarning, match=r"\"tri\".*not a closed mesh"):
        i = s.import_obstacle(str(tmp_path / "tri.obj"), name="tri", position=[0, 0.5, 0])
    assert i == 2 and s.obstacle_count == 3
    s.undo()
    assert s.obstacle_count == 2
    with pytest.raises(tendril.Error, match="missing.obj"):
        s.import_obstacle(str(tmp_path / "missing.obj"))
    assert s.obstacle_count == 2


def test_wind_frames_move_the_plant():
    scene = wall_scene(steps=60)
    scene["environment"]["wind"] = {"mode": "gusty", "velocity": [6, 0, 0], "gust_strength": 0.4}
    s = tendril.Session(scene)
    s.run()
    parts = s.mesh().parts
    frames = s.wind_frames(seconds=1.0, fps=8)
    assert len(frames) == 8
    for f in frames:
        assert [a.shape for a in f] == [p.positions.shape for p in parts]
    moved = max(np.abs(frames[3][i] - frames[0][i]).max() for i in range(len(parts)))
    assert moved > 1e-4
    with pytest.raises(tendril.Error, match="fps: must be in"):
        s.wind_frames(1.0, 0)
    # The same plant in another wind: calm air does not move it, a stronger one more.
    calm = s.wind_frames(1.0, 8, wind={"velocity": [0, 0, 0]})
    assert max(np.abs(calm[3][i] - calm[0][i]).max() for i in range(len(parts))) < 1e-6
    strong = s.wind_frames(1.0, 8, wind={"mode": "gusty", "velocity": [15, 0, 0], "gust_strength": 0.4})
    assert max(np.abs(strong[3][i] - strong[0][i]).max() for i in range(len(parts))) > moved
    with pytest.raises(tendril.Error, match=r"/wind/velocity"):
        s.wind_frames(1.0, 8, wind={"velocity": "strong"})


def test_two_sessions_grow_at_once_in_threads():
    def grow(i, out):
        s = tendril.Session(wall_scene(steps=40, seed=10 + i))
        s.run()
        out[i] = s.state_hash

    alone = {}
    for i in range(2):
        grow(i, alone)
    together = {}
    threads = [threading.Thread(target=grow, args=(i, together)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert together == alone


def test_growing_releases_the_gil():
    # While one thread grows (after its first step), Python code runs on in another. Were the
    # GIL held through run(), the loop below could not turn until the growth ended.
    s = tendril.Session(wall_scene(steps=800, model="particles", species="ivy-particles"))  # a second or two
    started = threading.Event()
    grower = threading.Thread(target=lambda: s.run(progress=lambda done: started.set()))
    grower.start()
    started.wait()
    ticks = 0
    while grower.is_alive():
        ticks += 1
    grower.join()
    assert s.step_count == 800
    assert ticks > 1000


def test_export_and_render(tmp_path):
    s = tendril.Session(wall_scene(steps=30))
    s.run()
    s.export(str(tmp_path / "ivy.obj"))
    assert (tmp_path / "ivy.obj").stat().st_size > 1000
    with pytest.raises(tendril.Error, match=r"\.glb or \.obj"):
        s.export(str(tmp_path / "ivy.fbx"))
    s.render(str(tmp_path / "ivy.png"), 160, 120)
    assert (tmp_path / "ivy.png").read_bytes()[:4] == b"\x89PNG"


def test_the_python_example_runs(tmp_path):
    example = SOURCE / "examples" / "python" / "ivy_on_a_column.py"
    subprocess.run(["/usr/bin/python3" if Path("/usr/bin/python3").exists() else "python3", str(example), str(tmp_path)],
                   check=True, capture_output=True, env=dict(os.environ, MPLBACKEND="Agg"))
    for name in ("column.png", "stem-length-by-order.png", "column.glb"):
        assert (tmp_path / name).stat().st_size > 1000, name


def test_warnings_reach_python():
    scene = wall_scene(steps=400, model="particles", species={"model": "particles", "max_particles": 40})
    # An open mesh (one triangle) is accepted with a warning.
    scene["environment"]["obstacles"].append(
        tendril.mesh_obstacle([[2, 0, 2], [3, 0, 2], [2, 1, 2]], [[0, 1, 2]], name="sheet"))
    with pytest.warns(tendril.TendrilWarning, match="sheet.*not a closed mesh"):
        s = tendril.Session(scene)
    with pytest.warns(tendril.TendrilWarning, match="reached max_particles"):
        s.run(200)
    assert any("not a closed mesh" in w for w in s.warnings)
    assert any("max_particles" in w for w in s.warnings)
    healthy = tendril.Session(wall_scene(steps=20))
    healthy.run()
    assert healthy.warnings == []


def test_a_plant_that_stops_early_says_why():
    # Ivy seeded 1.5 m in front of the wall: nothing to climb, its shoots die in a few steps.
    scene = wall_scene(steps=60)
    scene["plants"].append({"name": "lost", "model": "climb", "position": [0.0, 0.0, 1.5]})
    s = tendril.Session(scene)
    with pytest.warns(tendril.TendrilWarning, match='plant "lost" stopped growing.*no support in reach'):
        s.run()
    problems = s.growth_problems()
    assert [(p["plant"], p["cause"], p["stopped"]) for p in problems] == [(1, "no-support", True)]
    assert problems[0]["message"] in s.warnings
    healthy = tendril.Session(wall_scene(steps=60))
    healthy.run()
    assert healthy.growth_problems() == []



def test_pivot_painter_textures_are_what_the_cli_writes(tmp_path):
    """output.pivot_painter through Python's Session.export: the .glb and both textures per plant,
    byte for byte what `tendril grow` writes for the same scene (docs/export.md)."""
    scene = json.loads((SCENES / "default.json").read_text())
    scene["steps"] = 40
    scene.setdefault("output", {})["pivot_painter"] = True
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(json.dumps(scene))
    cli_out = tmp_path / "cli"
    subprocess.run([CLI, "grow", str(scene_file), "-o", str(cli_out), "--format", "glb", "--quiet"], check=True)
    s = tendril.Session.open(str(scene_file))
    s.run()
    py_out = tmp_path / "py"
    py_out.mkdir()
    s.export(str(py_out / "plant.glb"))
    textures = sorted(p.name for p in cli_out.glob("plant-*-pp-*"))
    assert len(textures) == 2 * s.plant_count
    assert sorted(p.name for p in py_out.glob("plant-*-pp-*")) == textures
    for name in textures + ["plant.glb"]:
        assert sha(py_out / name) == sha(cli_out / name), name
    # The .obj alone carries nothing of it, and writes no textures.
    obj_out = tmp_path / "obj"
    obj_out.mkdir()
    s.export(str(obj_out / "plant.obj"))
    assert not list(obj_out.glob("*-pp-*"))

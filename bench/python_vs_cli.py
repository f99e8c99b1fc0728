#!/usr/bin/python3
"""Growing the default scene from Python against the CLI (bench/README.md, "Python module").

    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_vs_cli.py build/release/tendril [runs] [scene]

Both grow examples/scenes/default.json and write plant.glb (checked to be the same bytes).
Per run, alternating:
* what each measures itself, in a fresh process per run: the CLI's log line ("growth": opening
  the scene's session and growing it; "total": and writing plant.glb) against the same spans
  timed around Session.open + run() and + export() in the Python process;
* the whole job as a process (informational): `tendril grow SCENE -o DIR --format glb` against
  `python3 -c "import tendril; ..."`, interpreter start and module import included.
Prints the medians and the ratios.
"""

import hashlib
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "scenes" / "default.json"


def main() -> None:
    cli = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build" / "release" / "tendril")
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 9
    scene = Path(sys.argv[3]) if len(sys.argv) > 3 else SCENE
    tmp = Path(tempfile.mkdtemp())
    # A fresh process per run for both (the first export in a process encodes the built-in
    # textures; a warm process would flatter either side).
    py_job = ("import sys, time, tendril; t = time.perf_counter(); s = tendril.Session.open(sys.argv[1]); "
              "s.run(); g = time.perf_counter() - t; s.export(sys.argv[2]); "
              "print(g, time.perf_counter() - t)")
    cli_job, python_job, cli_growth, python_growth, cli_total, python_total = [], [], [], [], [], []
    for _ in range(runs):
        t = time.perf_counter()
        out = subprocess.run([cli, "grow", str(scene), "-o", str(tmp / "cli"), "--format", "glb"],
                             check=True, capture_output=True, text=True)
        cli_job.append(time.perf_counter() - t)
        m = re.search(r"growth ([0-9.]+) s, total ([0-9.]+) s", out.stdout + out.stderr)
        cli_growth.append(float(m.group(1)))
        cli_total.append(float(m.group(2)))
        t = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", py_job, str(scene), str(tmp / "py.glb")], check=True,
                             env=dict(os.environ), capture_output=True, text=True)
        python_job.append(time.perf_counter() - t)
        growth, total = (float(x) for x in out.stdout.split())
        python_growth.append(growth)
        python_total.append(total)
    same = hashlib.sha256((tmp / "cli" / "plant.glb").read_bytes()).digest() == \
        hashlib.sha256((tmp / "py.glb").read_bytes()).digest()
    med = statistics.median
    print(f"{scene.name}, runs: {runs}; the same plant.glb from both: {same}")
    for what, c, p in (("growth", cli_growth, python_growth), ("growth + export", cli_total, python_total),
                       ("whole process", cli_job, python_job)):
        print(f"{what:16s} CLI {med(c) * 1e3:7.1f} ms   Python {med(p) * 1e3:7.1f} ms   ratio {med(p) / med(c):.3f}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()

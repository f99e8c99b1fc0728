#!/usr/bin/python3
"""Growing the default scene from Python against the CLI (bench/README.md, "Python module").

    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_vs_cli.py build/release/tendril [runs]

Both grow examples/scenes/default.json and write plant.glb. Timed per run, alternating:
* the whole job as a process: `tendril grow SCENE -o DIR --format glb --quiet` against
  `python3 -c "import tendril; s = tendril.Session.open(SCENE); s.run(); s.export(...)"`
  (interpreter start and module import included);
* the growth alone: the CLI's own "growth" figure (its log line) against Session.run() timed
  in one Python process.
Prints the medians and the ratios. Leaves out: nothing of the job; the files written are
checked to be the same bytes.
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
    import tendril

    tmp = Path(tempfile.mkdtemp())
    py_job = ("import tendril, sys; s = tendril.Session.open(sys.argv[1]); s.run(); "
              "s.export(sys.argv[2])")
    cli_job, python_job, cli_growth, python_growth = [], [], [], []
    for _ in range(runs):
        t = time.perf_counter()
        out = subprocess.run([cli, "grow", str(SCENE), "-o", str(tmp / "cli"), "--format", "glb"],
                             check=True, capture_output=True, text=True)
        cli_job.append(time.perf_counter() - t)
        cli_growth.append(float(re.search(r"growth ([0-9.]+) s", out.stdout + out.stderr).group(1)))
        t = time.perf_counter()
        subprocess.run([sys.executable, "-c", py_job, str(SCENE), str(tmp / "py.glb")], check=True,
                       env=dict(os.environ))
        python_job.append(time.perf_counter() - t)
        s = tendril.Session.open(str(SCENE))
        t = time.perf_counter()
        s.run()
        python_growth.append(time.perf_counter() - t)
    same = hashlib.sha256((tmp / "cli" / "plant.glb").read_bytes()).digest() == \
        hashlib.sha256((tmp / "py.glb").read_bytes()).digest()
    med = statistics.median
    print(f"runs: {runs}; the same plant.glb from both: {same}")
    print(f"whole job  CLI {med(cli_job) * 1e3:7.1f} ms   Python {med(python_job) * 1e3:7.1f} ms   "
          f"ratio {med(python_job) / med(cli_job):.3f}")
    print(f"growth     CLI {med(cli_growth) * 1e3:7.1f} ms   Python {med(python_growth) * 1e3:7.1f} ms   "
          f"ratio {med(python_growth) / med(cli_growth):.3f}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Ivy on a column made in numpy: grow it, read its skeleton as arrays, plot stem length per
branch order (docs/python.md). Run from the repository with the module built:

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/ivy_on_a_column.py out/

Writes out/column.png (Tendril's own render), out/stem-length-by-order.png and out/column.glb.
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import tendril


def column(radius=0.18, height=2.4, segments=32):
    """A closed cylinder standing on y = 0 (Tendril is y up): vertices and triangles."""
    a = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.stack([radius * np.cos(a), np.zeros_like(a), radius * np.sin(a)], axis=1)
    top = ring + [0.0, height, 0.0]
    vertices = np.concatenate([ring, top, [[0.0, 0.0, 0.0], [0.0, height, 0.0]]])
    tris = []
    for i in range(segments):
        j = (i + 1) % segments
        tris += [(i, segments + i, j), (j, segments + i, segments + j)]  # side, facing out
        tris += [(2 * segments, i, j), (2 * segments + 1, segments + j, segments + i)]  # caps
    return vertices, np.array(tris)


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    vertices, triangles = column()
    scene = {
        "tendril": 1,
        "seed": 4,
        "steps": 240,
        "environment": {
            "obstacles": [
                {"name": "ground", "type": "plane", "size": [6, 6], "color": [0.35, 0.42, 0.3]},
                tendril.mesh_obstacle(vertices, triangles, name="column", color=[0.75, 0.72, 0.66]),
            ],
            "lights": [{"type": "directional", "direction": [-0.3, -1, -0.4]}],
        },
        "plants": [
            {"name": f"ivy{k}", "species": "japanese-ivy", "seed": k,
             "position": [0.2 * np.cos(a), 0.0, 0.2 * np.sin(a)]}
            for k, a in enumerate(np.linspace(0.3, 2 * np.pi + 0.3, 3, endpoint=False), start=1)
        ],
        "output": {"radial_segments": 8, "subdivisions": 3},
    }
    s = tendril.Session(scene)
    # Progress on a terminal: run() calls back after every step.
    progress = (lambda done: print(f"\rgrowing: step {done}", end="", flush=True)) if sys.stdout.isatty() else None
    steps = s.run(progress=progress)
    print(f"\rgrew {s.plant_count} plants in {steps} steps: {s.segment_count} segments")

    # Stem length per branch order, over every plant: one bar per order.
    totals = {}
    for i in range(s.plant_count):
        p = s.plant(i)
        for order in np.unique(p.orders):
            totals[int(order)] = totals.get(int(order), 0.0) + float(p.lengths[p.orders == order].sum())
        print(f"{p.name}: {p.node_count} segments, {p.leaf_count} leaves, "
              f"highest tip {p.tips()[:, 1].max():.2f} m")
    orders = sorted(totals)
    fig, ax = plt.subplots(figsize=(5, 3.2), dpi=120)
    ax.bar([str(o) for o in orders], [totals[o] for o in orders], color="#4a7a3a")
    ax.set_xlabel("branch order (0: main stems)")
    ax.set_ylabel("stem length (m)")
    ax.set_title("Ivy on a column: stem length per branch order")
    fig.tight_layout()
    fig.savefig(out / "stem-length-by-order.png")

    s.render(str(out / "column.png"), 800, 600)
    s.export(str(out / "column.glb"))
    print(f"wrote {out / 'column.png'}, {out / 'stem-length-by-order.png'}, {out / 'column.glb'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "out"))

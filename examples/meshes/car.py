#!/usr/bin/python3
"""Writes car.obj beside this file: a low-poly car for seed 000's Fig. 1 scene
(examples/scenes/particles-fig01-car.json), lofted through cross-sections along its length so
that it is one closed, consistently wound mesh (signed distances, nothing inside it).

Metres, y up, the car's front toward +x, 4 m long and 1.7 m wide, its floor 0.3 m above the
ground (the wheels are the scene's cylinders). Each station is (x, belt line, top, top half
width): below the belt line the body is 1.7 m wide, above it the greenhouse narrows to the
roof; at the hood and the trunk the top is just above the belt line.

Run: /usr/bin/python3 examples/meshes/car.py
"""
import os

FLOOR, HALF_WIDTH = 0.3, 0.85
STATIONS = [
    (-2.00, 0.95, 0.97, 0.80),  # rear face
    (-1.90, 1.00, 1.02, 0.80),
    (-1.30, 1.02, 1.04, 0.80),  # end of the trunk, foot of the rear window
    (-0.95, 1.02, 1.45, 0.68),  # top of the rear window, roof
    (0.45, 1.02, 1.48, 0.68),   # roof's front edge, top of the windscreen
    (1.00, 1.00, 1.02, 0.80),   # foot of the windscreen
    (1.90, 0.92, 0.94, 0.80),
    (2.00, 0.75, 0.77, 0.80),   # front face
]


def section(x, belt, top, half):
    # Counter-clockwise seen from the front (+x): floor, right side, roof, left side.
    return [(x, FLOOR, HALF_WIDTH), (x, FLOOR, -HALF_WIDTH), (x, belt, -HALF_WIDTH), (x, top, -half),
            (x, top, half), (x, belt, HALF_WIDTH)]


def main():
    rings = [section(*s) for s in STATIONS]
    n = len(rings[0])
    vertices = [v for ring in rings for v in ring]
    faces = []
    for r in range(len(rings) - 1):
        a, b = r * n, (r + 1) * n
        for k in range(n):
            k2 = (k + 1) % n
            faces.append((a + k, b + k, b + k2))
            faces.append((a + k, b + k2, a + k2))
    last = (len(rings) - 1) * n
    for k in range(1, n - 1):
        faces.append((0, k + 1, k))                  # rear cap, facing -x
        faces.append((last, last + k, last + k + 1))  # front cap, facing +x
    # Every face outward: its normal points away from the car's middle line.
    out = []
    for f in faces:
        p = [vertices[i] for i in f]
        u = [p[1][j] - p[0][j] for j in range(3)]
        w = [p[2][j] - p[0][j] for j in range(3)]
        nrm = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        c = [sum(q[j] for q in p) / 3 for j in range(3)]
        mid = (max(min(c[0], 1.9), -1.9), 0.8, 0.0)
        if sum(nrm[j] * (c[j] - mid[j]) for j in range(3)) < 0:
            f = (f[0], f[2], f[1])
        out.append(f)
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "car.obj")
    with open(path, "w") as obj:
        obj.write("# A low-poly car for seed 000's Fig. 1 (written by examples/meshes/car.py)\n")
        for v in vertices:
            obj.write("v %.3f %.3f %.3f\n" % v)
        for f in out:
            obj.write("f %d %d %d\n" % (f[0] + 1, f[1] + 1, f[2] + 1))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""How far one step of the particle solver can amplify a disturbance of a straight chain.

A linear model of ParticleWorld's shape matching (src/tendril/particles/dynamics.cpp) for a
chain of n particles hanging off a fixed root, small transverse motion in a plane: per
particle an offset y across the chain and the angle t of its frame. One step is what the
solver does:

* predict: y += v, t += w (velocities per step, kept by the factor 1 - damping);
* `passes` Gauss-Seidel passes from the root outward; particle i, after its parent i-1 moved
  in this pass and before its child i+1 does, goes the share s (stiffness) of the way to
      own * (its group's rigid fit: the mean of y[i-1], y[i], y[i+1], turned by their slope)
    + (1 - own) * (its parent's target: y[i-1] + l t[i-1], frame t[i-1])
  (eq. 3-4 and section 4.3 as implemented: the parent's target taken in the parent's frame);
* integrate: the new velocities are the positions' change over the step.

The step is linear, y' = M y for the state (y, t, v, w). Its spectral radius says whether a
disturbance dies out in the end; G = max_k |M^k| (2-norm) says how much it can grow on the
way. A solver that follows the parents one way is far from normal: its G grows with the
chain's length by orders of magnitude while the spectral radius stays below 1, and the
measured chains whip accordingly (docs/particles.md, "Known limits").

Simplifications: equal masses, unit spacing, the particles' own moments left out of the
group fits, no gravity (it adds a constant, not a mode). Run with Debian's /usr/bin/python3
(numpy). Example: scripts/analysis/particle_solver_stability.py --particles 12 40 80
"""

import argparse
import sys

import numpy as np


def step_matrix(n, stiffness=1.0, own=1.0 / 3.0, passes=3, damping=0.0, carry=True):
    """The solver's step as a matrix on the state (y, t, v, w), each of length n."""
    if n < 2:
        raise ValueError("a chain needs at least 2 particles")
    if not (0.0 < stiffness <= 1.0) or not (0.0 <= own <= 1.0) or passes < 1 or not (0.0 <= damping < 1.0):
        raise ValueError("stiffness in (0, 1], own weight in [0, 1], passes >= 1, damping in [0, 1)")
    dim = 4 * n
    basis = np.eye(dim)  # every unit state at once: row i of Y is particle i's offset in each
    y, t, v, w = basis[:n], basis[n:2 * n], basis[2 * n:3 * n], basis[3 * n:]
    Y = y + v
    T = t + w
    zero = np.zeros(dim)
    for _ in range(passes):
        for i in range(n):
            y_parent = Y[i - 1] if i > 0 else zero  # the root stays where it is
            t_parent = T[i - 1] if i > 0 else zero
            if i + 1 < n:
                fit_y = (y_parent + Y[i] + Y[i + 1]) / 3.0
                fit_t = (Y[i + 1] - y_parent) / 2.0
            else:
                fit_y = (y_parent + Y[i]) / 2.0
                fit_t = Y[i] - y_parent
            goal_y = own * fit_y + (1.0 - own) * (y_parent + t_parent)
            goal_t = own * fit_t + (1.0 - own) * t_parent
            Y[i] = Y[i] + stiffness * (goal_y - Y[i])
            T[i] = T[i] + stiffness * (goal_t - T[i])
    keep = (1.0 - damping) if carry else 0.0
    return np.vstack([Y, T, keep * (Y - y), keep * (T - t)])


def spectral_radius(m):
    return float(np.max(np.abs(np.linalg.eigvals(m))))


def transient_growth(m, steps=400):
    """max over k <= steps of |M^k| (2-norm)."""
    power = np.eye(m.shape[0])
    best = 1.0
    for _ in range(steps):
        power = m @ power
        best = max(best, float(np.linalg.norm(power, 2)))
        if not np.isfinite(best):
            return float("inf")
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--particles", type=int, nargs="+", default=[12, 40, 80])
    parser.add_argument("--stiffness", type=float, nargs="+", default=[1.0, 0.4])
    parser.add_argument("--own", type=float, default=1.0 / 3.0, help="own group's weight (eq. 4; the solver: 1/3)")
    parser.add_argument("--passes", type=int, default=3, help="shape-matching passes per step (the solver: 3)")
    parser.add_argument("--damping", type=float, default=0.0, help="velocity lost per step")
    parser.add_argument("--no-carry", action="store_true", help="no velocity kept from step to step")
    parser.add_argument("--steps", type=int, default=400, help="steps over which G is taken")
    args = parser.parse_args(argv)
    print("particles stiffness  spectral-radius  transient-growth")
    for n in args.particles:
        for s in args.stiffness:
            try:
                m = step_matrix(n, s, args.own, args.passes, args.damping, not args.no_carry)
            except ValueError as e:
                print(f"error: {e}", file=sys.stderr)
                return 2
            print(f"{n:9d} {s:9.2f}  {spectral_radius(m):15.3f}  {transient_growth(m, args.steps):16.3g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

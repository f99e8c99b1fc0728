# ABOP §1.10.2, eq. 1.9 and Fig. 1.37: a parametric L-system, the "row of trees". Each
# segment splits into four whose lengths keep the proportions p : h : h : q (6 steps here).
lsystem: row-of-trees
derivation length: 6
angle: 86
width: 0.004
define: c = 1, p = 0.3
define: q = c - p, h = (p * q) ^ 0.5
axiom: F(1)
F(x) -> F(x*p) + F(x*h) - - F(x*h) + F(x*q)

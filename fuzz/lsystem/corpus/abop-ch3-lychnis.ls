# ABOP chapter 3 (developmental models of herbaceous plants, p. 84): Lychnis coronaria, a
# sympodial plant. An apex A(t) matures for 7 steps, then makes an internode I(20), a pair of
# leaves, two lateral apices — the second 4 steps older than the first, so the branches
# alternate in vigour — and a flower K that ends its axis. Internodes elongate two segments a
# step while their counter runs down. One unit of ABOP's turtle is 5 mm here.
lsystem: lychnis-coronaria
derivation length: 26
step: 0.005
width: 0.004
colors: (0.25, 0.45, 0.15), (0.8, 0.1, 0.35)
# Five rhombic petals spread around the heading, in colour 1.
surface: K = '(1) [&(60) {. -(30) f(1) . +(60) f(1) . +(120) f(1) .}] /(72) [&(60) {. -(30) f(1) . +(60) f(1) . +(120) f(1) .}] /(72) [&(60) {. -(30) f(1) . +(60) f(1) . +(120) f(1) .}] /(72) [&(60) {. -(30) f(1) . +(60) f(1) . +(120) f(1) .}] /(72) [&(60) {. -(30) f(1) . +(60) f(1) . +(120) f(1) .}]
axiom: A(7)
A(t) : t == 7 -> F I(20) [&(60) ~leaf(0.05, 0, 0.005)] /(90) [&(45) A(0)] /(90) [&(60) ~leaf(0.05, 0, 0.005)] /(90) [&(45) A(4)] F I(10) ~K(0.02)
A(t) : t < 7 -> A(t + 1)
I(t) : t > 0 -> F F I(t - 1)

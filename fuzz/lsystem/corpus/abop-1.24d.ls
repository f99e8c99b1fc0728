# ABOP Fig. 1.24d: a node-rewriting plant, n = 7, δ = 20°.
lsystem: abop-1.24d
derivation length: 7
angle: 20
width: 0.25
axiom: X
X -> F[+X]F[-X]+X
F -> FF

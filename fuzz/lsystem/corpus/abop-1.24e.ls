# ABOP Fig. 1.24e: n = 7, δ = 25.7°.
lsystem: abop-1.24e
derivation length: 7
angle: 25.7
width: 0.25
axiom: X
X -> F[+X][-X]FX
F -> FF

# ABOP Fig. 1.24a: a bracketed (edge-rewriting) plant, n = 5, δ = 25.7°.
lsystem: abop-1.24a
derivation length: 5
angle: 25.7
width: 0.25
axiom: F
F -> F[+F]F[-F]F

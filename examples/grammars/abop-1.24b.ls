# ABOP Fig. 1.24b: n = 5, δ = 20°.
lsystem: abop-1.24b
derivation length: 5
angle: 20
width: 0.25
axiom: F
F -> F[+F]F[-F][F]

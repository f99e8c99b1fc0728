# ABOP Fig. 1.24f: n = 5, δ = 22.5°.
lsystem: abop-1.24f
derivation length: 5
angle: 22.5
width: 0.25
axiom: X
X -> F-[[X]+X]+F[+FX]-X
F -> FF

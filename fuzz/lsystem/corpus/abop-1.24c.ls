# ABOP Fig. 1.24c: n = 4, δ = 22.5°.
lsystem: abop-1.24c
derivation length: 4
angle: 22.5
width: 0.25
axiom: F
F -> FF-[-F+F+F]+[+F-F-F]

# tendril-studio tests: a small bracketed weed (ABOP Fig. 1.24a with 1 cm segments).
lsystem: weed
derivation length: 4
angle: 25.7
step: 0.01
width: 0.003
axiom: F
F -> F[+F]F[-F]F

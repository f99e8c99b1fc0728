# ABOP §1.7, Fig. 1.27: a stochastic L-system. Each F becomes one of three successors with
# probabilities 0.33, 0.33 and 0.34; every seed gives a different plant of the same kind.
lsystem: abop-1.27
seed: 1
derivation length: 5
angle: 25.7
width: 0.25
axiom: F
F -> F[+F]F[-F]F : 0.33
F -> F[+F]F      : 0.33
F -> F[-F]F      : 0.34

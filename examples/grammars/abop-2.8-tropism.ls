# ABOP §2.4, Fig. 2.8a: a ternary tree bent by tropism. After every segment the turtle turns
# toward T by e·|H × T| (ABOP eq. 2.6); units are ABOP's, one unit = 1 cm here.
lsystem: ternary-tree
derivation length: 6
define: d1 = 94.74, d2 = 132.63, a = 18.95, lr = 1.109, vr = 1.732, cm = 0.01
tropism: 0, -1, 0
elasticity: 0.22
axiom: !(cm) F(200*cm) /(45) A
A : * -> !(vr*cm) F(50*cm) [&(a) F(50*cm) A] /(d1) [&(a) F(50*cm) A] /(d2) [&(a) F(50*cm) A]
F(l) : * -> F(l*lr)
!(w) : * -> !(w*vr)

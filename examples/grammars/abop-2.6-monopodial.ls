# ABOP §2.2, Fig. 2.6a: Honda's monopodial tree. The trunk A shrinks by r1 per segment and
# issues branches B at angle a0 with divergence d; branches alternate C and B laterals in
# their own plane ($ keeps it horizontal).
lsystem: monopodial-tree
derivation length: 10
define: r1 = 0.9, r2 = 0.6, a0 = 45, a2 = 45, d = 137.5, wr = 0.707
axiom: A(1, 10)
A(l, w) : * -> !(w/100) F(l) [&(a0) B(l*r2, w*wr)] /(d) A(l*r1, w*wr)
B(l, w) : * -> !(w/100) F(l) [-(a2) $ C(l*r2, w*wr)] C(l*r1, w*wr)
C(l, w) : * -> !(w/100) F(l) [+(a2) $ B(l*r2, w*wr)] B(l*r1, w*wr)

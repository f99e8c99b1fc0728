module: Apex(l)
axiom: Apex(1) ?P(0, 0, 0) ?H(0, 0, 0) ?E(SURFACE, 1, 0, 0, 0, 0) ?E(HIT, 1, 0) ?E(LIGHT, 0, 0, 0, 0) ?E(ATTRACT, 0, 0, 0) ?E(FACING, 1, 50, 0, 0, 0, 0)
Apex(l) > ?P(x, y, z) ?H(a, b, c) ?E(k, r, d, e, f, g) : d < 0 -> F(l) @R(a, b + 1, c, 0, 0, 1) Apex(l * 0.9) ?P(0, 0, 0) ?H(0, 0, 0) ?E(SURFACE, 1, 0, 0, 0, 0)
?P -> *
?H -> *
?E -> *

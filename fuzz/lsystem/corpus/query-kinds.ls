derivation length: 6
axiom: A(1)
A(k) -> ?E(k, 1, 0, 0, 0, 0) A(k + 1)
interpretation:
A(k) : k > 4 -> ?E(k - 3, 2, 0)

derivation length: 3
axiom: A [B] %
A -> A B : 0.5
A -> [C%D] E : 0.5
decomposition:
maximum depth: 3
B -> C D
C -> E
interpretation:
maximum depth: 2
E -> F(1) +(30) ~leaf(0.2)
D -> {. f . + f . } @O(0.1)

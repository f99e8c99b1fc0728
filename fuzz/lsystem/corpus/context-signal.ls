ignore: + F
axiom: b a [ + a a ] a [ a ] a
b < a -> b
b -> a
A(x) < B(y) > [C(z)] D : y > 0 -> B(y + 1)

axiom: A(0)
A(x) -> B(1/x)

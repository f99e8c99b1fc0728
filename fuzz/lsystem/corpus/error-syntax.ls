axiom: A
A -> B(1 +)

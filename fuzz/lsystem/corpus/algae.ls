# Lindenmayer's model of the alga Anabaena catenula (ABOP §1.2): the string lengths
# follow the Fibonacci numbers 1, 2, 3, 5, 8, 13, ...
lsystem: algae
derivation length: 10
axiom: A
A -> A B
B -> A

# Drawn as a filament: long cells A, short cells B, slightly bent.
interpretation:
A -> +(4) !(0.35) F(1)
B -> -(3) !(0.25) F(0.6)

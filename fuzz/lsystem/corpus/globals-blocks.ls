derivation length: 4
define: k = 2
global: total = 10
Start: { steps = 0; }
StartEach: { steps += 1; }
EndEach: { if (steps == 2) { marker = k * 100; } else marker = marker + 1; }
End: { done = total + steps; }
axiom: A(0)
A(n) : { y = n * 2; } y >= 0 { z = y + 1; } -> A(n + steps) B(z, ran(1), nran(0, 1))
B(a, b, c) -> *

# ABOP Fig. 1.31a (after Hogeweg and Hesper): a context-sensitive L-system. Signals 0 and 1
# travel along the branches; + and - and F are ignored when contexts are matched, and the
# left context skips whole branches on its way to the root (ABOP §1.8).
lsystem: abop-1.31a
derivation length: 30
angle: 22.5
width: 0.25
ignore: + - F
axiom: F1F1F1
0 < 0 > 0 -> 0
0 < 0 > 1 -> 1[+F1F1]
0 < 1 > 0 -> 1
0 < 1 > 1 -> 1
1 < 0 > 0 -> 0
1 < 0 > 1 -> 1F1
1 < 1 > 0 -> 0
1 < 1 > 1 -> 0
+ -> -
- -> +

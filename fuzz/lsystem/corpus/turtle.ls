angle: 30
width: 0.2
tropism: 0, -1, 0
elasticity: 0.2
surface: petal = { . + f . - f . - f . }
colors: (1, 0, 0), (0, 1, 0)
leaf shapes: "builtin:ivy-0" 1.0, "builtin:heart-0" 0.8
axiom: F [ & F ^ F \ F / F | F $ F ] ! F !(0.3) ' F '(3) ~petal(2) ~leaf(1, 1, 0.1) @M(1, 2, 3) f F @Tv(1, 0, 0) @Te(0.5) F @Climb(1) F

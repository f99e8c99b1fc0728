# ABOP Fig. 1.26 (after the "plant with flowers" listing): internodes, polygon leaves and
# five-wedge flowers. Multi-letter modules are declared; { . } polygons are traced with f and
# closed into two-sided surfaces; '(i) picks their colour.
lsystem: flowering-plant
derivation length: 5
angle: 18
width: 0.06
colors: (0.16, 0.42, 0.1), (0.22, 0.55, 0.12), (0.95, 0.85, 0.2), (0.9, 0.9, 0.85)
module: plant, internode, seg, leaf, flower, pedicel, wedge
axiom: plant
plant -> internode + [plant + flower] - - / / [- - leaf] internode [+ + leaf] - [plant flower] + + plant flower
internode -> F seg [/ / & & leaf] [/ / ^ ^ leaf] F seg
seg -> seg F seg
leaf -> ['(1) { . + f . - f f . - f . + | + f . - f f . - f . } ]
flower -> [& & & pedicel '(2) / wedge / / / / wedge / / / / wedge / / / / wedge / / / / wedge]
pedicel -> F F
wedge -> [^ F] [{ & & & & . - f . + f . | - f . + f . }]

# Japanese ivy (Parthenocissus tricuspidata) as an L-system whose tips query their
# environment: seed 003's Program 1 and Table 1 written with ?E (docs/grammar.md).
#
# Each derivation step every tip (Apex) reads the answers of the query modules that follow it,
# filled in when the previous step's string was interpreted:
#   ?H ?U                      its heading and up vector
#   ?E(FACING, REACH, ...)     its support: the closest surface within the adhesion distance
#                              that it is not growing away from (§3.6)
#   [Cut f(l) ?E(SURFACE ..)   where its next segment would end: the closest surface there,
#    ?E(FACING ..)]            and the support there
#   ?E(HIT, l + OFFSET, ...)   an obstacle hit along that segment (seed 003 §3.5)
#   ?E(LIGHT ..) ?E(ATTRACT ..) light, and painted attractors (eq. 6) and the regions repelling
#                              strokes keep clear
# and then does one thing: turns away from a collision (eq. 5), bends back toward a surface it
# is about to leave (the climbing heuristic, §3.6), or grows one segment whose ray was clear —
# so no segment ever passes through an obstacle — and applies Table 1's rules: tropism
# (eq. 3-4, 6-7), decrease (eq. 8), leaf, branch and die, each every `l` segments with
# probability `p` (Program 1). Leaves are fitted in two more steps: their blade outline is
# probed with rays and shrunk until it touches nothing, and it lies parallel to the surface
# nearest to it, upper side away from it (§3.10).
lsystem: japanese-ivy
seed: 1
derivation length: 400
leaf shapes: "builtin:ivy-0" 1.0, "builtin:ivy-1" 1.0, "builtin:ivy-2" 1.0
bark: "builtin:bark" (0.42, 0.32, 0.22)
leaf thickness: 0.0004

# Shoot start values and seed 003 eq. 8's decrease per segment (0.97, 0.97, 0.94).
define: L0 = 0.04, R0 = 0.006, S0 = 0.1
define: DR = 0.97, DL = 0.97, DS = 0.94, LMIN = 0.006, RMIN = 0.0008
# A lateral shoot starts from its parent shoot's start values times these.
define: FR = 0.8, FL = 0.95, FS = 0.95
# Tropism strengths (eq. 6-7).
define: GRAVITY = 0.12, LIGHT_T = 0.08, AMBIENT = 0.3, RANDOM_T = 0.16, ADHESION = 0.35, ATTRACTION = 0.5
# Climbing: adhesion distance (m), release angle (deg), stand-off from surfaces (m), the chance
# to hold on at an edge, segments a tip survives without support, turns before it gives up.
define: REACH = 0.08, RELEASE = 50, OFFSET = 0.012, HOLD = 0.95, MAXU = 6, TURNS = 6
# Table 1's rules: every n-th segment, with a probability.
define: LEAF_EVERY = 2, BRANCH_EVERY = 3, BRANCH_P = 0.6, DIE_EVERY = 10, DIE_P = 0.02
# Branching 35-40 degrees off the growth direction (§3.7); lateral shoots of at most this order.
define: BRANCH_MIN = 35, BRANCH_MAX = 40, MAX_ORDER = 2
# Leaves: spread of the pair (deg), its jitter, petiole and lift over the stem (m), blade aspect.
define: SPREAD = 55, JITTER = 12, PETIOLE = 0.01, LIFT = 0.004, ASPECT = 1

module: Apex(l, r, s, l0, r0, s0, n, u, o, k), Tip(l, r, s, l0, r0, s0, n, u, o, k, dead)
module: LeafBud(on, s, r), Bud(s, r), Blade(s, scale, shape), Fit(s, scale, shape)
module: Shoot(on, angle, roll, l, r, s, u, o), Cut

# Probes are looked through when contexts are matched.
ignore: f + - & ^ \ Cut

axiom: f(OFFSET) Tip(L0, R0, S0, L0, R0, S0, 0, 0, 0, 0, 0)

production:

# --- the tip: Program 1 ------------------------------------------------------------------

# Die: too short (eq. 8 ran out), too long without support, boxed in, or in a region a
# repelling stroke keeps clear.
Apex(l, r, s, l0, r0, s0, n, u, o, k) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(q1, r1, c1, d, ax, ay, az) [?E(q2, r2, de, bx, by, bz) ?E(q6, r6, c6, df, fx, fy, fz)] ?E(q3, r3, t, nx, ny, nz) ?E(q4, e, lx, ly, lz) ?E(q5, px, py, pz, kept) : l < LMIN || (d < 0 && u >= MAXU) || k > TURNS || kept > 0 -> *

# Collision avoidance (eq. 5): the segment ahead would hit a surface. Turn the tip parallel
# to it (d' = d - n(n.d)), its up vector along the normal, and look again next step.
Apex(l, r, s, l0, r0, s0, n, u, o, k) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(q1, r1, c1, d, ax, ay, az) [?E(q2, r2, de, bx, by, bz) ?E(q6, r6, c6, df, fx, fy, fz)] ?E(q3, r3, t, nx, ny, nz) ?E(q4, e, lx, ly, lz) ?E(q5, px, py, pz, kept) : t >= 0 {
    dn = dot(hx, hy, hz, nx, ny, nz);
    vx = hx - nx * dn; vy = hy - ny * dn; vz = hz - nz * dn;
    if (norm(vx, vy, vz) < 0.05) {   # head-on: slide the way the up vector leans
      du = dot(ux, uy, uz, nx, ny, nz);
      vx = ux - nx * du; vy = uy - ny * du; vz = uz - nz * du;
    }
    if (norm(vx, vy, vz) < 0.05) { vx = ny; vy = -nx; vz = 0; }
    if (norm(vx, vy, vz) < 0.05) { vx = 0; vy = nz; vz = -ny; }
  } -> @R(vx, vy, vz, nx, ny, nz) Tip(l, r, s, l0, r0, s0, n, u, o, k + 1, 0)

# Hold on (the climbing heuristic): a climbing tip whose next segment would end out of reach of
# every surface bends back toward the surface nearest that end — over an edge, round a corner
# — unless it breaks free (1 - HOLD of the time).
Apex(l, r, s, l0, r0, s0, n, u, o, k) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(q1, r1, c1, d, ax, ay, az) [?E(q2, r2, de, bx, by, bz) ?E(q6, r6, c6, df, fx, fy, fz)] ?E(q3, r3, t, nx, ny, nz) ?E(q4, e, lx, ly, lz) ?E(q5, px, py, pz, kept) : d >= 0 && de > REACH && ran(1) < HOLD {
    tx = l * hx + (OFFSET - de) * bx; ty = l * hy + (OFFSET - de) * by; tz = l * hz + (OFFSET - de) * bz;
  } -> @R(tx, ty, tz, bx, by, bz) Tip(l, r, s, l0, r0, s0, n, u, o, k + 1, 0)

# Grow: the ray along the heading was clear, so Tip -> segment(Tip) Tip; then Table 1.
Apex(l, r, s, l0, r0, s0, n, u, o, k) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(q1, r1, c1, d, ax, ay, az) [?E(q2, r2, de, bx, by, bz) ?E(q6, r6, c6, df, fx, fy, fz)] ?E(q3, r3, t, nx, ny, nz) ?E(q4, e, lx, ly, lz) ?E(q5, px, py, pz, kept) : * {
    # Climbing (§3.6): the tip has a support; `near`: the segment's end will have one.
    climb = d >= 0;
    near = df >= 0;
    # Tropism vector, eq. 6 and 7: near a surface adhesion replaces gravity. The adhesive pull
    # reverses inside the stand-off distance, so the shoot settles OFFSET off its support.
    if (near) {
      w = clamp((df - OFFSET) / (REACH - OFFSET), -1, 1);
      vx = -ADHESION * w * fx; vy = -ADHESION * w * fy; vz = -ADHESION * w * fz;
    } else {
      vx = 0; vy = -GRAVITY; vz = 0;
    }
    g = e > 0 ? LIGHT_T * e : LIGHT_T * AMBIENT;
    vx += g * lx; vy += g * ly; vz += g * lz;
    rx = nran(0, 1); ry = nran(0, 1); rz = nran(0, 1);
    rn = max(norm(rx, ry, rz), 0.000001);
    vx += RANDOM_T * rx / rn; vy += RANDOM_T * ry / rn; vz += RANDOM_T * rz / rn;
    vx += ATTRACTION * px; vy += ATTRACTION * py; vz += ATTRACTION * pz;
    # Eq. 3-4: rotate the heading toward v about H x v, by |H x v| but never past v.
    cx = hy * vz - hz * vy; cy = hz * vx - hx * vz; cz = hx * vy - hy * vx;
    sn = norm(cx, cy, cz);
    cs = dot(hx, hy, hz, vx, vy, vz);
    mx = hx; my = hy; mz = hz;
    if (sn > 0.0000001) {
      phi = min(sn * 180 / PI, atan2(sn, cs));
      mx = cos(phi) * hx + sin(phi) * (vx - hx * cs) / sn;
      my = cos(phi) * hy + sin(phi) * (vy - hy * cs) / sn;
      mz = cos(phi) * hz + sin(phi) * (vz - hz * cs) / sn;
    }
    # The frame's up vector faces away from the support (PlantModel's +Z).
    wx = near ? fx : (climb ? ax : ux); wy = near ? fy : (climb ? ay : uy); wz = near ? fz : (climb ? az : uz);
    m = n + 1;
    leaf = m % LEAF_EVERY == 0;
    branch = m % BRANCH_EVERY == 0 && o < MAX_ORDER && ran(1) < BRANCH_P;
    dead = m % DIE_EVERY == 0 && ran(1) < DIE_P;
    angle = (ran(1) < 0.5 ? 1 : -1) * uniform(BRANCH_MIN, BRANCH_MAX);
    roll = near ? 0 : ran(360);   # climbing shoots branch in the surface's plane
  } -> @Climb(climb) !(2 * max(r, RMIN)) F(l) LeafBud(leaf, s, r) Shoot(branch, angle, roll, l0 * FL, r0 * FR, s0 * FS, climb ? 0 : u + 1, o + 1) @R(mx, my, mz, wx, wy, wz) Tip(l * DL, r * DR, s * DS, l0, r0, s0, m, climb ? 0 : u + 1, o, 0, dead)

# --- leaves (§3.8, §3.10) ----------------------------------------------------------------

# A leaf node: no room over the stem, or no blades; otherwise a pair of blades lying in the
# plane of the nearest surface (or the stem's, in the air), spread either side of the stem.
?E(qa, la, t0) < Bud(s, r) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(qb, rb, dk, kx, ky, kz) : t0 >= 0 -> *
Bud(s, r) > ?H(hx, hy, hz) ?U(ux, uy, uz) ?E(qb, rb, dk, kx, ky, kz) : {
    upx = dk >= 0 ? kx : ux; upy = dk >= 0 ? ky : uy; upz = dk >= 0 ? kz : uz;
    c = dot(hx, hy, hz, upx, upy, upz);
    bx = hx - upx * c; by = hy - upy * c; bz = hz - upz * c;
  } norm(bx, by, bz) > 0.1 -> [@R(bx, by, bz, upx, upy, upz) +(SPREAD + JITTER * uniform(-1, 1)) Fit(s, 1, floor(ran(3)))] [@R(bx, by, bz, upx, upy, upz) -(SPREAD + JITTER * uniform(-1, 1)) Fit(s, 1, floor(ran(3)))]
Bud(s, r) -> *

# A blade whose outline touched nothing becomes a leaf; one that did is tried smaller, then
# dropped (the leaf fitting of the climbing model).
Blade(s, scale, shape) > [?E(q1, a1, t1) ?E(q2, a2, t2) ?E(q3, a3, t3) ?E(q4, a4, t4) ?E(q5, a5, t5)] : t1 < 0 && t2 < 0 && t3 < 0 && t4 < 0 && t5 < 0 -> ~leaf(s * scale, shape, PETIOLE * scale)
Blade(s, scale, shape) : scale > 0.5 -> Fit(s, scale > 0.9 ? 0.7 : 0.45, shape)
Blade(s, scale, shape) -> *

# --- probes are answered once, then replaced by fresh ones -------------------------------
Cut -> %
?E -> *
?H -> *
?U -> *

decomposition:
maximum depth: 3

# A tip with its probes, or nothing when it died.
Tip(l, r, s, l0, r0, s0, n, u, o, k, dead) : dead -> *
Tip(l, r, s, l0, r0, s0, n, u, o, k, dead) -> Apex(l, r, s, l0, r0, s0, n, u, o, k) ?H(0, 0, 0) ?U(0, 0, 0) ?E(FACING, REACH, RELEASE, 0, 0, 0, 0) [Cut f(l) ?E(SURFACE, l + REACH, 0, 0, 0, 0) ?E(FACING, REACH, RELEASE, 0, 0, 0, 0)] ?E(HIT, l + OFFSET, 0, 0, 0, 0) ?E(LIGHT, 0, 0, 0, 0) ?E(ATTRACT, 0, 0, 0, 0)

# A leaf node lifted over the stem along the up vector (after checking that way is free).
LeafBud(on, s, r) : on -> [^(90) ?E(HIT, r + LIFT, 0) f(r + LIFT) &(90) Bud(s, r) ?H(0, 0, 0) ?U(0, 0, 0) ?E(SURFACE, REACH, 0, 0, 0, 0)]
LeafBud(on, s, r) -> *

# A lateral shoot turned 35-40 degrees off the stem.
Shoot(on, angle, roll, l, r, s, u, o) : on -> [\(roll) +(angle) Tip(l, r, s, l, r, s, 0, u, o, 0, 0)]
Shoot(on, angle, roll, l, r, s, u, o) -> *

# A blade to fit: rays along its outline, attachment -> c0 -> c1 -> c2 -> c3 -> c0 (the leaf
# quad of mesh/leaf_mesh.h: c0, c1 at the petiole end, c2, c3 at the tip).
Fit(s, scale, shape) : {
    size = s * scale; pet = PETIOLE * scale; hw = 0.5 * size * ASPECT;
    a0 = atan2(hw, pet); d0 = norm(hw, pet); w2 = 2 * hw;
  } -> Blade(s, scale, shape) [Cut +(a0) ?E(HIT, d0, 0) f(d0) -(a0 + 90) ?E(HIT, w2, 0) f(w2) +(90) ?E(HIT, size, 0) f(size) +(90) ?E(HIT, w2, 0) f(w2) +(90) ?E(HIT, size, 0)]

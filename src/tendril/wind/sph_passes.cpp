// The SPH air's passes (the equations are in sph.cpp's opening comment): the plants' side of
// the coupling (collecting their bodies, eq. 13's anisotropic kernel, drag and pressure back onto
// them) and the substeps of the weakly compressible and position-based solvers, each compiled
// for the baseline instruction set and for AVX2.
#include "tendril/wind/sph.h"

#include "tendril/core/parallel.h"
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/wind/sph_detail.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

namespace tendril::wind {

// The plants' bodies (grown branch particles) that can reach the domain, in the order of their
// bins, and each listed in the bins its support's bounding box meets.
void SphAir::collectPlants(std::span<const models::AirBodies> bodies) {
  Plants& P = *plants_;
  P.clear();
  std::vector<uint32_t> found, foundBody;
  const Vec3 lo = settings_.domainMin, hi = settings_.domainMax;
  for (uint32_t b = 0; b < bodies.size(); ++b) {
    const models::AirBodies& B = bodies[b];
    for (const uint32_t i : B.ids) {
      const float reach = B.halfLength[i] + h_;
      const Vec3& x = B.position[i];
      if (!isFinite(x) || ((x.array() < (lo.array() - reach)).any() || (x.array() > (hi.array() + reach)).any()))
        continue;
      found.push_back(i);
      foundBody.push_back(b);
    }
  }
  // Counting sort by the cell of the centre, stable in (system, slot).
  const size_t n = found.size(), cells = size_t(P.dims.x()) * P.dims.y() * P.dims.z();
  std::vector<uint32_t> cellOf(n), first(cells + 1, 0);
  for (size_t k = 0; k < n; ++k) {
    cellOf[k] = P.binOf(bodies[foundBody[k]].position[found[k]]);
    ++first[cellOf[k] + 1];
  }
  for (size_t c = 1; c < first.size(); ++c) first[c] += first[c - 1];
  P.slot.resize(n), P.body.resize(n), P.x.resize(n), P.axis.resize(n), P.v.resize(n), P.invA2.resize(n), P.invB2.resize(n);
  P.detG.resize(n), P.volume.resize(n), P.dragK.assign(n, 0.0f), P.invZ.assign(n, 0.0f), P.extent.resize(n);
  P.packX.resize(n), P.packAxis.resize(n), P.psiG.resize(n), P.packV.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const uint32_t j = first[cellOf[k]]++;
    const uint32_t i = found[k];
    const models::AirBodies& B = bodies[foundBody[k]];
    const float a = B.halfLength[i], b = B.radius[i];
    // eq. 13: G maps the particle's support ellipsoid — its own ellipsoid grown by the air's
    // support h along every axis — onto the unit ball: G = R diag(1/α, 1/β, 1/β) Rᵀ. The
    // isotropic ablation: a ball of the particle's volume grown by h, α = β = ∛(a b²) + h.
    float alpha = a + h_, beta = b + h_;
    if (settings_.kernel == SphKernel::Isotropic) alpha = beta = std::cbrt(a * b * b) + h_;
    P.slot[j] = i;
    P.body[j] = foundBody[k];
    P.x[j] = B.position[i];
    P.axis[j] = (B.orientation[i] * Vec3::UnitY()).normalized();
    P.v[j] = B.velocity[i];
    P.invA2[j] = 1.0f / (alpha * alpha);
    P.invB2[j] = 1.0f / (beta * beta);
    P.detG[j] = 1.0f / (alpha * beta * beta);
    P.volume[j] = 4.0f / 3.0f * kPi * a * b * b;
    P.packX[j] = V4f{P.x[j].x(), P.x[j].y(), P.x[j].z(), P.invA2[j]};
    P.packAxis[j] = V4f{P.axis[j].x(), P.axis[j].y(), P.axis[j].z(), P.invB2[j]};
    P.psiG[j] = P.volume[j] * P.detG[j];
    // The support ellipsoid's bounding box.
    for (int c = 0; c < 3; ++c) {
      const float e2 = P.axis[j][c] * P.axis[j][c];
      P.extent[j][c] = std::sqrt(alpha * alpha * e2 + beta * beta * std::max(0.0f, 1.0f - e2));
    }
  }
  // Bin: each plant particle into every cell its box meets (boxes clamped to the grid, whose
  // outermost cells reach to infinity). In parallel over the layers of cells along z, each
  // layer's cells counted and filled by one task in plant order, so every cell's list is the
  // same for any thread count.
  std::vector<Eigen::Vector3i> c0(n), c1(n);
  std::vector<int> centreLayer(n);
  parallelFor(0, n, [&](size_t j) {
    for (int k = 0; k < 3; ++k) {
      c0[j][k] = std::clamp(int(std::floor((P.x[j][k] - P.extent[j][k] - P.origin[k]) * P.inv)), 0, P.dims[k] - 1);
      c1[j][k] = std::clamp(int(std::floor((P.x[j][k] + P.extent[j][k] - P.origin[k]) * P.inv)), 0, P.dims[k] - 1);
    }
    centreLayer[j] = int(P.binOf(P.x[j]) / (uint32_t(P.dims.x()) * uint32_t(P.dims.y())));
  }, 1024);
  // The plants are in the order of their centres' bins (z-major): those whose box can meet a
  // layer have their centre within `reach` layers of it, a contiguous range.
  int reach = 0;
  for (uint32_t j = 0; j < n; ++j) reach = std::max({reach, centreLayer[j] - c0[j].z(), c1[j].z() - centreLayer[j]});
  auto forLayer = [&](int z, auto&& f) {
    const auto from = std::lower_bound(centreLayer.begin(), centreLayer.end(), z - reach);
    const auto to = std::upper_bound(from, centreLayer.end(), z + reach);
    for (uint32_t j = uint32_t(from - centreLayer.begin()); j < uint32_t(to - centreLayer.begin()); ++j) {
      if (z < c0[j].z() || z > c1[j].z()) continue;
      for (int y = c0[j].y(); y <= c1[j].y(); ++y)
        for (int x = c0[j].x(), c = int(P.binIndex(x, y, z)); x <= c1[j].x(); ++x, ++c) f(c, j);
    }
  };
  P.start.assign(cells + 1, 0);
  parallelFor(0, size_t(P.dims.z()), [&](size_t z) { forLayer(int(z), [&](int c, uint32_t) { ++P.start[size_t(c) + 1]; }); }, 1);
  for (size_t c = 1; c < P.start.size(); ++c) P.start[c] += P.start[c - 1];
  // Every entry is written below; only the padding needs its zeros (no 8 MB memset per frame).
  P.entries.resize(P.start.back() + 8);
  std::fill(P.entries.end() - 8, P.entries.end(), 0u);
  std::vector<uint32_t> next(P.start.begin(), P.start.end() - 1);
  parallelFor(0, size_t(P.dims.z()), [&](size_t z) {
    forLayer(int(z), [&](int c, uint32_t j) { P.entries[next[size_t(c)]++] = j; });
  }, 1);
}

namespace {

// What a substep's passes share.
struct PassConstants {
  size_t n = 0;
  float h = 0, h2 = 0, invH2 = 0, m = 0, rho0 = 0, c2 = 0, background = 0, norm6 = 0, search = 0;
  float kp = 0, kv = 0;  // the pressure and viscosity forces' folded constants
  bool closed = false, hasPlants = false;  // closed: any face of the domain box is a wall
  // Position-based solver: m/ρ0, 1/ρ0, the spiky gradient's 45/(π h⁶), the relaxation ε of
  // the constraint's denominator, the artificial pressure's k/(denominator at rest) and
  // 1/W(Δq) (as (1 − Δq²/h²)³), the particle's rest distance from a wall (s/4).
  float volume = 0, invRho0 = 0, spikyH = 0, eps = 0, corr = 0, invWq = 0, rmin = 0;
  // Position-based solver: in a closed domain the constraint also pulls thin air together,
  // down to a deficit of `tension` (the background pressure's share; 0 with an open face).
  float tension = 0;
  Vec3 dmin = Vec3::Zero(), dmax = Vec3::Zero();
  // The closed faces' planes; ∓∞ for open ones, so their mirrored lattices add nothing.
  Vec3 wallMin = Vec3::Zero(), wallMax = Vec3::Zero();
};

// Room for `more` entries after `used` in a block's buffer.
inline uint32_t* room(std::vector<uint32_t>& buffer, size_t used, size_t more) {
  if (buffer.size() < used + more) buffer.resize(std::max(used + more, 2 * buffer.size()));
  return buffer.data();
}

// Density (eq. 12 with A = ρ: ρ_i = Σ m W_poly6) plus the walls' mirrored lattices, for the
// particles of one block; the same pass lists the neighbours 0 < r < h for the forces.
template <class Grid, class Walls>
[[gnu::always_inline]] inline void densityBlock(Grid& g, const Walls& W, const PassConstants& c, size_t block) {
  std::vector<uint32_t>& buffer = g.nbrBlocks[block];
  size_t used = 0;
  const float h2 = c.h2, invH2 = c.invH2;
  for (size_t k = block * kBlock, end = std::min(c.n, k + kBlock); k < end; ++k) {
    const float x = g.px[k], y = g.py[k], z = g.pz[k];
    g.nbrBegin[k] = uint32_t(used);
    // Eight candidates at a time (the arrays are padded), lanes past the run masked off; eight
    // partial sums, added in a fixed order. A run holds about eight candidates.
    const V8f x8 = splat8(x), y8 = splat8(y), z8 = splat8(z);
    V8f sum8 = splat8(0.0f);
    g.forSphereRuns(x, y, z, c.search, [&](uint32_t b, uint32_t e) {
      uint32_t* out = room(buffer, used, e - b + 8);
      for (uint32_t j = b; j < e; j += 8) {
        const V8f dx = load8(&g.px[j]) - x8, dy = load8(&g.py[j]) - y8, dz = load8(&g.pz[j]) - z8;
        const V8f r2 = dx * dx + dy * dy + dz * dz;
        const V8i near = (kLanes8 < int32_t(e) - int32_t(j)) & (r2 < h2);
        const V8f t = masked8(near, 1.0f - r2 * invH2);
        sum8 += t * t * t;
        const unsigned mask = movemask8(near & (r2 > 0.0f));
        used += appendLanes(mask & 15u, j, out + used);
        used += appendLanes(mask >> 4, j + 4, out + used);
      }
    });
    g.nbrCount[k] = uint32_t(used - g.nbrBegin[k]);
    float rho = c.m * c.norm6 * total8(sum8);
    rho += W.lookup(W.density, g.sdf[k]);
    if (c.closed) rho += boxGhostDensity(W, Vec3(x, y, z) - c.wallMin, c.wallMax - Vec3(x, y, z));  // walls
    g.rho[k] = rho;
  }
  // Eight valid indices past the block's last list: the passes read lists eight at a time and
  // mask off the lanes past a particle's count.
  std::fill_n(room(buffer, used, 8) + used, 8, 0u);
}

// Plants add to the density like boundary particles of volume Ψ (eq. 12–13), push the air by
// pressure and drag it; then the equation of state. One pass over each air particle's bin: the
// plants do not move within a frame, so every plant term is a sum over the supports holding
// the particle of factors that depend only on the pair, times the particle's own ρ, p or v:
//   ρ      += ρ0 Σ Ψ W_j
//   a_push  = −(p/ρ) Σ Ψ ∇W_spiky,j,  ∇W = det G (−45/π)(1 − |η|)² G²u/|η|,
//             G²u = (u·e) e/α² + (u − (u·e) e)/β²   (mirrored pressure on a boundary particle)
//   a_drag  = (1/m) Σ φ k (v_j − v)⊥,  φ = V W_j / max(Z, ½), V = m/ρ   (the air's share of the
//             plant particle's drag; Σ φ k / m is the implicit factor)
// so the sums are gathered first and scaled once ρ and p are known.
// The position-based solver (PositionBased = true) keeps the plants' density ρ0 Σ Ψ W_j and
// constraint gradient Σ Ψ ∇W_j for its projections instead, and the drag as above.
template <bool PositionBased, class Grid, class Plants>
[[gnu::always_inline]] inline void plantBlock(Grid& g, const Plants& P, const PassConstants& c, size_t block) {
  const float rho0 = c.rho0, c2 = c.c2, background = c.background;
  const V4f* packX = P.packX.data();
  const V4f* packAxis = P.packAxis.data();
  const V4f* packV = P.packV.data();
  for (size_t k = block * kBlock, end = std::min(c.n, k + kBlock); k < end; ++k) {
    float rho = g.rho[k];
    uint32_t hits = 0;
    if (c.hasPlants) {
      const Vec3 x(g.px[k], g.py[k], g.pz[k]);
      const uint32_t bin = P.binOf(x), b = P.start[bin], e = P.start[bin + 1];
      // Eight candidates at a time (their packed state transposed into lanes; lanes past the
      // list read the next bin's entries or the padding and are masked off), sums in eight
      // lanes; the pressure and drag terms only for trips holding a hit.
      const V8f x8 = splat8(x.x()), y8 = splat8(x.y()), z8 = splat8(x.z());
      const V8f vx8 = splat8(g.vx[k]), vy8 = splat8(g.vy[k]), vz8 = splat8(g.vz[k]);
      V8f sum8 = splat8(0.0f), sx = sum8, sy = sum8, sz = sum8, dx = sum8, dy = sum8, dz = sum8, rate8 = sum8;
      for (uint32_t q = b; q < e; q += 8) {
        const uint32_t* j = &P.entries[q];
        V8f jx, jy, jz, invA2, ex, ey, ez, invB2;
        transpose8(packX, j, &jx, &jy, &jz, &invA2);
        transpose8(packAxis, j, &ex, &ey, &ez, &invB2);
        const V8f ux = x8 - jx, uy = y8 - jy, uz = z8 - jz;
        const V8f along = ux * ex + uy * ey + uz * ez, a2 = along * along;
        const V8f e2 = a2 * invA2 + (ux * ux + uy * uy + uz * uz - a2) * invB2;  // eq. 13
        const V8i hit = (kLanes8 < int32_t(e - q)) & (e2 < 1.0f);
        const unsigned mask = movemask8(hit);
        if (mask == 0) continue;
        hits += uint32_t(__builtin_popcount(mask));
        const V8f psiG = {P.psiG[j[0]], P.psiG[j[1]], P.psiG[j[2]], P.psiG[j[3]],
                          P.psiG[j[4]], P.psiG[j[5]], P.psiG[j[6]], P.psiG[j[7]]};
        const V8f w = 1.0f - e2, w3 = w * w * w;
        sum8 += masked8(hit, psiG * w3);
        const V8f eta = sqrt8(e2), te = 1.0f - eta;
        const V8f coef = masked8(hit & (eta > 1e-6f), psiG * te * te / eta);
        const V8f ga = along * invA2 - along * invB2;  // G²u = ga e + u/β²
        sx += coef * (ga * ex + invB2 * ux);
        sy += coef * (ga * ey + invB2 * uy);
        sz += coef * (ga * ez + invB2 * uz);
        V8f jvx, jvy, jvz, dragShareG;
        transpose8(packV, j, &jvx, &jvy, &jvz, &dragShareG);
        const V8f kk = masked8(hit, w3 * dragShareG);
        V8f rx = jvx - vx8, ry = jvy - vy8, rz = jvz - vz8;
        const V8f ra = rx * ex + ry * ey + rz * ez;
        rx -= ra * ex, ry -= ra * ey, rz -= ra * ez;
        dx += kk * rx, dy += kk * ry, dz += kk * rz;
        rate8 += kk;
      }
      if constexpr (PositionBased) {
        // Σ Ψ ∇W_j = −45/π Σ Ψ det G (1 − |η|)² G²u/|η|; the drag's share with the density so far.
        const float plantRho = (rho0 * kPoly6) * total8(sum8), share = kPoly6 / (rho + plantRho);
        g.plantRho[k] = plantRho;
        g.plantGrad[k] = -kSpiky * Vec3(total8(sx), total8(sy), total8(sz));
        g.dragAcc[k] = share * Vec3(total8(dx), total8(dy), total8(dz));
        g.dragRate[k] = share * total8(rate8);
        g.hitCount[k] = hits;
        continue;
      }
      rho += (rho0 * kPoly6) * total8(sum8);
      const float p = std::max(0.0f, c2 * (rho - rho0) + background);
      const float push = p > 0.0f ? p / rho * kSpiky : 0.0f, share = kPoly6 / rho;
      g.plantAcc[k] = push * Vec3(total8(sx), total8(sy), total8(sz));
      g.dragAcc[k] = share * Vec3(total8(dx), total8(dy), total8(dz));
      g.dragRate[k] = share * total8(rate8);
      g.rho[k] = rho;
    }
    g.hitCount[k] = hits;
    if constexpr (PositionBased) {
      g.plantRho[k] = 0.0f, g.plantGrad[k] = Vec3::Zero();
      continue;
    }
    const float p = std::max(0.0f, c2 * (rho - rho0) + background);
    g.pressure[k] = p;
    g.invRho[k] = 1.0f / rho;
    g.pOverRho[k] = p / rho;
    g.packedX[k] = V4f{g.px[k], g.py[k], g.pz[k], g.invRho[k]};
    g.packedV[k] = V4f{g.vx[k], g.vy[k], g.vz[k], g.pOverRho[k]};
  }
}

// Pressure and viscosity (eq. 11, MCG03 eq. 10 and 14) over the listed neighbours, the walls'
// pressure and the plants' push, for the particles begin..end:
// −m (p_i + p_j)/(2ρ_j) ∇W_spiky, ∇W_spiky = −45/(π h⁶)(h − r)² r̂, and
// μ m (v_j − v_i)/ρ_j ∇²W_visc, ∇²W_visc = 45/(π h⁶)(h − r), with their constants folded.
template <class Grid, class Walls>
[[gnu::always_inline]] inline void forcesRange(Grid& g, const Walls& W, const PassConstants& c, size_t begin,
                                               size_t end) {
  const V4f* packedX = g.packedX.data();
  const V4f* packedV = g.packedV.data();
  const float h = c.h, kp = c.kp, kv = c.kv;
  for (size_t k = begin; k < end; ++k) {
    const V4f xk = packedX[k], vk = packedV[k];
    const float x = xk[0], y = xk[1], z = xk[2], pk = g.pressure[k];
    const V8f x8 = splat8(x), y8 = splat8(y), z8 = splat8(z), vx8 = splat8(vk[0]), vy8 = splat8(vk[1]),
              vz8 = splat8(vk[2]);
    const uint32_t* list = g.nbrBlocks[k / kBlock].data() + g.nbrBegin[k];
    const uint32_t count = g.nbrCount[k];
    V8f ax8 = splat8(0.0f), ay8 = ax8, az8 = ax8;
    // Eight neighbours at a time, each one's packed state transposed into lanes; lanes past
    // the list (the next particle's entries, or the block's padding) are masked off.
    for (uint32_t q = 0; q < count; q += 8) {
      const uint32_t* j = list + q;  // lanes past the count read the next list or the padding
      V8f px8, py8, pz8, invRho8, pvx8, pvy8, pvz8, pOverRho8;
      transpose8(packedX, j, &px8, &py8, &pz8, &invRho8);
      transpose8(packedV, j, &pvx8, &pvy8, &pvz8, &pOverRho8);
      const V8f dx = x8 - px8, dy = y8 - py8, dz = z8 - pz8;
      const V8f r = sqrt8(dx * dx + dy * dy + dz * dz), t = h - r;
      const V8i live = kLanes8 < int32_t(count - q);
      const V8f fp = masked8(live, kp * (pk * invRho8 + pOverRho8) * t * t / r);
      const V8f fv = masked8(live, kv * invRho8 * t);
      ax8 += fp * dx + fv * (pvx8 - vx8);
      ay8 += fp * dy + fv * (pvy8 - vy8);
      az8 += fp * dz + fv * (pvz8 - vz8);
    }
    const float rho = g.rho[k];
    Vec3 a = Vec3(total8(ax8), total8(ay8), total8(az8)) / rho;
    // Walls: a = −p/(ρ0 ρ) g_w(d) n.
    const float wall = -pk / (c.rho0 * rho);
    if (c.closed) a += wall * boxGhostGradient(W, Vec3(x, y, z) - c.wallMin, c.wallMax - Vec3(x, y, z));
    if (pk > 0.0f && g.sdf[k] < h) a += wall * W.lookup(W.gradient, g.sdf[k]) * g.sdfNormal[k];
    if (c.hasPlants) a += g.plantAcc[k];  // the plants' pressure push, from the plant pass
    g.acc[k] = a;
  }
}

// Position-based solver (Macklin & Müller 2013, "Position Based Fluids", PBF), one Jacobi
// iteration in two passes over the listed neighbours at the particles' current positions
// (packedX, (x, y, z, ·)). With V = m/ρ0 and ∇W = ∇W_spiky = −45/(π h⁶)(h − r)² r̂:
//   C_i   = max(ρ_i/ρ0 − 1, −b) (PBF eq. 1; b the background pressure's share in a closed
//           domain, 0 with an open face: there air only pushes, as in the equation of state),
//           ρ_i = Σ_j m W_poly6 + the walls' mirrored lattices + ρ0 Σ_b Ψ W_b (plants)
//   ∇_i C = V Σ_j ∇W_ij + (walls' g_w n + the box's ghost gradient)/ρ0 + Σ_b Ψ ∇W_b,
//   ∇_j C = −V ∇W_ij                                                          (PBF eq. 8)
//   λ_i   = −C_i / (|∇_i C|² + V² Σ_j |∇W_ij|² + ε)                            (PBF eq. 11)
// then
//   Δx_i  = V Σ_j (λ_i + λ_j + s_corr) ∇W_ij + λ_i (∇_i C − V Σ_j ∇W_ij)       (PBF eq. 12)
// the last term the walls' and plants' part (they have no constraint of their own), and
// s_corr = −k (W(r)/W(Δq))⁴ (PBF eq. 13, in units of a constraint at rest: k/(denominator at
// rest)) only where the constraint also pulls, against clumping.
template <class Grid, class Walls>
[[gnu::always_inline]] inline void lambdaRange(Grid& g, const Walls& W, const PassConstants& c, size_t begin,
                                               size_t end) {
  const V4f* packedX = g.packedX.data();
  const float h = c.h, h2 = c.h2, invH2 = c.invH2, spikyH = c.spikyH;
  for (size_t k = begin; k < end; ++k) {
    const V4f xk = packedX[k];
    const float x = xk[0], y = xk[1], z = xk[2];
    const V8f x8 = splat8(x), y8 = splat8(y), z8 = splat8(z);
    const uint32_t* list = g.nbrBlocks[k / kBlock].data() + g.nbrBegin[k];
    float* pairGrad = g.pairBlocks[k / kBlock].data() + g.nbrBegin[k];
    const uint32_t count = g.nbrCount[k];
    V8f d8 = splat8(0.0f), gx8 = d8, gy8 = d8, gz8 = d8, g28 = d8;
    for (uint32_t q = 0; q < count; q += 8) {
      const uint32_t* j = list + q;  // lanes past the count read the next list or the padding
      V8f px8, py8, pz8, unused;
      transpose8(packedX, j, &px8, &py8, &pz8, &unused);
      const V8f dx = x8 - px8, dy = y8 - py8, dz = z8 - pz8;
      const V8f r2 = dx * dx + dy * dy + dz * dz;
      const V8i live = (kLanes8 < int32_t(count - q)) & (r2 < h2);
      const V8f t = masked8(live, 1.0f - r2 * invH2);
      d8 += t * t * t;
      const V8f r = sqrt8(r2), u = h - r;
      const V8f gs = masked8(live & (r > 0.0f), spikyH * u * u / r);  // |∇W| / r
      gx8 -= gs * dx, gy8 -= gs * dy, gz8 -= gs * dz;
      g28 += gs * gs * r2;
      // For the projection at the same positions (only this particle's entries: the next
      // particle's may be another thread's).
      std::memcpy(pairGrad + q, &gs, sizeof(float) * std::min(count - q, 8u));
    }
    const Vec3 p(x, y, z);
    // The walls at the current position: the box's faces exactly, obstacles by the distance
    // where the substep's query was, moved along its normal.
    const float d = g.sdf[k] + g.sdfNormal[k].dot(g.shift[k]);
    float rho = c.m * c.norm6 * (1.0f + total8(d8)) + W.lookup(W.density, d) + g.plantRho[k];
    Vec3 wall = W.lookup(W.gradient, d) * g.sdfNormal[k];
    if (c.closed) {
      rho += boxGhostDensity(W, p - c.wallMin, c.wallMax - p);
      wall += boxGhostGradient(W, p - c.wallMin, c.wallMax - p);
    }
    const Vec3 ext = c.invRho0 * wall + g.plantGrad[k];
    const Vec3 grad = c.volume * Vec3(total8(gx8), total8(gy8), total8(gz8)) + ext;
    const float constraint = std::max(rho * c.invRho0 - 1.0f, -c.tension);
    const float lambda = -constraint / (grad.squaredNorm() + c.volume * c.volume * total8(g28) + c.eps);
    g.rho[k] = rho;
    g.packedX2[k] = V4f{x, y, z, lambda};
    g.lambdaSum[k] += lambda;
    g.extGrad[k] = ext;
  }
}

// Reads (x, y, z, λ) from packedX2 (lambdaRange's output) and writes the moved positions to
// packedX.
template <class Grid>
[[gnu::always_inline]] inline void deltaRange(Grid& g, const PassConstants& c, size_t begin, size_t end) {
  const V4f* packed = g.packedX2.data();
  const float h2 = c.h2, invH2 = c.invH2, corr = c.corr, invWq = c.invWq;
  const bool pulls = c.tension > 0.0f;
  for (size_t k = begin; k < end; ++k) {
    const V4f xk = packed[k];
    const float x = xk[0], y = xk[1], z = xk[2], lk = xk[3];
    const V8f x8 = splat8(x), y8 = splat8(y), z8 = splat8(z), lk8 = splat8(lk);
    const uint32_t* list = g.nbrBlocks[k / kBlock].data() + g.nbrBegin[k];
    const float* pairGrad = g.pairBlocks[k / kBlock].data() + g.nbrBegin[k];
    const uint32_t count = g.nbrCount[k];
    V8f sx8 = splat8(0.0f), sy8 = sx8, sz8 = sx8;
    for (uint32_t q = 0; q < count; q += 8) {
      const uint32_t* j = list + q;  // lanes past the count read the next list or the padding
      V8f px8, py8, pz8, lj;
      transpose8(packed, j, &px8, &py8, &pz8, &lj);
      const V8f dx = x8 - px8, dy = y8 - py8, dz = z8 - pz8;
      const V8i live = kLanes8 < int32_t(count - q);
      V8f sum = lk8 + lj;
      if (pulls) {
        const V8f r2 = dx * dx + dy * dy + dz * dz;
        const V8f t = masked8(r2 < h2, 1.0f - r2 * invH2), w = t * t * t * invWq, w2 = w * w;
        sum -= corr * w2 * w2;
      }
      // (λ_i + λ_j + s) |∇W|/r, |∇W|/r from the λ pass (0 past h).
      const V8f coef = masked8(live, sum * load8(pairGrad + q));
      sx8 += coef * dx, sy8 += coef * dy, sz8 += coef * dz;
    }
    // ∇W_ij = −(|∇W|/r)(x_i − x_j).
    Vec3 p = Vec3(x, y, z) - c.volume * Vec3(total8(sx8), total8(sy8), total8(sz8)) + lk * g.extGrad[k];
    // Closed faces hold the particle s/4 inside; an obstacle, by its distance moved along the
    // normal (the move is a fraction of the spacing; the substep's end asks the SDF again).
    for (int a = 0; a < 3; ++a) p[a] = std::clamp(p[a], c.wallMin[a] + c.rmin, c.wallMax[a] - c.rmin);
    const Vec3 moved = g.shift[k] + (p - Vec3(x, y, z));
    const float d = g.sdf[k] + g.sdfNormal[k].dot(moved);
    if (d < c.rmin) p += (c.rmin - d) * g.sdfNormal[k];
    g.shift[k] += p - Vec3(x, y, z);
    g.packedX[k] = V4f{p.x(), p.y(), p.z(), 0.0f};
  }
}

// Once per frame, per plant particle j: the air around it with its kernel (eq. 12), Z = Σ V W_j
// and Σ V W_j v, and the reaction to the air's pressure acceleration −(p/ρ) Ψ ∇W_j (see
// plantBlock), Σ m (p/ρ) Ψ ∇W_j. The air particles are those within α (the support's longest
// semi-axis), eight at a time.
struct PlantGather {
  float z = 0.0f;
  Vec3 velocity = Vec3::Zero(), pressureForce = Vec3::Zero();
};
template <class Grid, class Plants>
[[gnu::always_inline]] inline PlantGather plantGather(const Grid& g, const Plants& P, float m, uint32_t j) {
  const Vec3 xj = P.x[j], axis = P.axis[j];
  const float invA2 = P.invA2[j], invB2 = P.invB2[j], detG = P.detG[j];
  const V8f jx = splat8(xj.x()), jy = splat8(xj.y()), jz = splat8(xj.z());
  const V8f ex = splat8(axis.x()), ey = splat8(axis.y()), ez = splat8(axis.z());
  V8f z8 = splat8(0.0f), vx8 = z8, vy8 = z8, vz8 = z8, fx8 = z8, fy8 = z8, fz8 = z8;
  const float weight = m * kPoly6 * detG, push = -m * P.volume[j] * kSpiky * detG;
  const float reach = (1.0f / std::sqrt(invA2)) * (1.0f + 1e-5f);  // α ≥ β
  g.forSphereRuns(xj.x(), xj.y(), xj.z(), reach, [&](uint32_t b, uint32_t e) {
    for (uint32_t k = b; k < e; k += 8) {
      const V8f ux = load8(&g.px[k]) - jx, uy = load8(&g.py[k]) - jy, uz = load8(&g.pz[k]) - jz;
      const V8f along = ux * ex + uy * ey + uz * ez, a2 = along * along;
      const V8f e2 = a2 * invA2 + (ux * ux + uy * uy + uz * uz - a2) * invB2;  // eq. 13
      const V8i hit = (kLanes8 < int32_t(e) - int32_t(k)) & (e2 < 1.0f);
      if (movemask8(hit) == 0) continue;
      const V8f rho = load8(&g.rho[k]), p = load8(&g.pressure[k]);
      const V8f t = 1.0f - e2;
      const V8f vw = masked8(hit, weight * t * t * t / rho);  // V W_j
      z8 += vw;
      vx8 += vw * load8(&g.vx[k]), vy8 += vw * load8(&g.vy[k]), vz8 += vw * load8(&g.vz[k]);
      // m (p/ρ) Ψ ∇W_j, ∇W_j = det G (−45/π)(1 − |η|)² G²u/|η|, G²u = ga e + u/β².
      const V8f eta = sqrt8(e2), te = 1.0f - eta;
      const V8f f = masked8(hit & (p > 0.0f) & (eta > 1e-6f), push * p / rho * te * te / eta);
      const V8f ga = along * invA2 - along * invB2;
      fx8 += f * (ga * ex + invB2 * ux);
      fy8 += f * (ga * ey + invB2 * uy);
      fz8 += f * (ga * ez + invB2 * uz);
    }
  });
  PlantGather out;
  out.z = total8(z8);
  out.velocity = Vec3(total8(vx8), total8(vy8), total8(vz8));
  out.pressureForce = Vec3(total8(fx8), total8(fy8), total8(fz8));
  return out;
}

// The passes twice: for the machine's baseline (SSE2 on x86-64) and, where the CPU has it, for
// AVX2 (one register per eight lanes; no FMA, so the same operations round the same way and
// the results are bit-identical). Everything they call is inlined into them (flatten).
#if TENDRIL_SPH_AVX2
template <class Grid, class Walls>
[[gnu::target("avx2"), gnu::flatten]] void densityAvx2(Grid& g, const Walls& W, const PassConstants& c, size_t block) {
  densityBlock(g, W, c, block);
}
template <bool PositionBased, class Grid, class Plants>
[[gnu::target("avx2"), gnu::flatten]] void plantAvx2(Grid& g, const Plants& P, const PassConstants& c, size_t block) {
  plantBlock<PositionBased>(g, P, c, block);
}
template <class Grid, class Walls>
[[gnu::target("avx2"), gnu::flatten]] void lambdaAvx2(Grid& g, const Walls& W, const PassConstants& c, size_t begin,
                                                     size_t end) {
  lambdaRange(g, W, c, begin, end);
}
template <class Grid>
[[gnu::target("avx2"), gnu::flatten]] void deltaAvx2(Grid& g, const PassConstants& c, size_t begin, size_t end) {
  deltaRange(g, c, begin, end);
}
template <class Grid, class Walls>
[[gnu::target("avx2"), gnu::flatten]] void forcesAvx2(Grid& g, const Walls& W, const PassConstants& c, size_t begin,
                                                     size_t end) {
  forcesRange(g, W, c, begin, end);
}
template <class Grid, class Plants>
[[gnu::target("avx2"), gnu::flatten]] PlantGather plantGatherAvx2(const Grid& g, const Plants& P, float m, uint32_t j) {
  return plantGather(g, P, m, j);
}
#endif
template <class Grid, class Plants>
[[gnu::flatten]] PlantGather plantGatherGeneric(const Grid& g, const Plants& P, float m, uint32_t j) {
  return plantGather(g, P, m, j);
}
template <class Grid, class Walls>
[[gnu::flatten]] void densityGeneric(Grid& g, const Walls& W, const PassConstants& c, size_t block) {
  densityBlock(g, W, c, block);
}
template <bool PositionBased, class Grid, class Plants>
[[gnu::flatten]] void plantGeneric(Grid& g, const Plants& P, const PassConstants& c, size_t block) {
  plantBlock<PositionBased>(g, P, c, block);
}
template <class Grid, class Walls>
[[gnu::flatten]] void lambdaGeneric(Grid& g, const Walls& W, const PassConstants& c, size_t begin, size_t end) {
  lambdaRange(g, W, c, begin, end);
}
template <class Grid>
[[gnu::flatten]] void deltaGeneric(Grid& g, const PassConstants& c, size_t begin, size_t end) {
  deltaRange(g, c, begin, end);
}
template <class Grid, class Walls>
[[gnu::flatten]] void forcesGeneric(Grid& g, const Walls& W, const PassConstants& c, size_t begin, size_t end) {
  forcesRange(g, W, c, begin, end);
}

std::atomic<bool> gGenericKernels{false};

bool useAvx2() {
#if TENDRIL_SPH_AVX2
  static const bool hasAvx2 = __builtin_cpu_supports("avx2");
  return hasAvx2 && !gGenericKernels.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

}  // namespace

// Once per frame, per plant particle: the air velocity around it (eq. 12 with its kernel), its
// drag coefficient for the frame, and the force the air exerts on it — drag plus the reaction
// to the pressure push it gives the air — as the external acceleration of eq. 1.
void SphAir::plantSide(std::span<models::AirCoupling* const> systems, std::span<const models::AirBodies> bodies) {
  Plants& P = *plants_;
  const Grid& g = *grid_;
  std::vector<std::vector<Vec3>*> externals;
  for (size_t b = 0; b < systems.size(); ++b) {
    externals.push_back(&systems[b]->airAcceleration());
    externals.back()->assign(bodies[b].slots, Vec3::Zero());
  }
  const float rho0 = settings_.restDensity, cd = settings_.dragCoefficient, dt = settings_.dt, m = mass_;
  const bool avx2 = useAvx2();
  parallelFor(0, P.size(), [&](size_t jj) {
    const uint32_t j = uint32_t(jj);
    PlantGather gather;
#if TENDRIL_SPH_AVX2
    if (avx2)
      gather = plantGatherAvx2(g, P, m, j);
    else
#endif
      gather = plantGatherGeneric(g, P, m, j);
    const float z = gather.z;
    P.invZ[j] = 1.0f / std::max(z, 0.5f);
    const uint32_t i = P.slot[j];
    const models::AirBodies& B = bodies[P.body[j]];
    // Stem drag in cross-flow: F = ½ ρ C_d (2a · 2b) |u⊥| u⊥, u⊥ the relative air velocity
    // across the axis (the axial part's skin friction is neglected).
    Vec3 rel = gather.velocity * P.invZ[j] - P.v[j];
    rel -= rel.dot(P.axis[j]) * P.axis[j];
    const float area = 4.0f * B.halfLength[i] * B.radius[i];
    P.dragK[j] = 0.5f * rho0 * std::min(z, 1.0f) * cd * area * rel.norm();
    P.packV[j] = V4f{P.v[j].x(), P.v[j].y(), P.v[j].z(), P.detG[j] * P.dragK[j] * P.invZ[j]};
    const float mj = B.mass[i];
    // Implicit in the drag, so a light particle never overshoots the air's velocity.
    (*externals[P.body[j]])[i] = P.dragK[j] * rel / (mj + P.dragK[j] * dt) + gather.pressureForce / mj;
  }, 64);
}

namespace {

// What every pass of a substep shares, from the settings.
PassConstants passConstants(const SphSettings& s, size_t n, float h, float m, float background, bool hasPlants) {
  PassConstants c;
  c.n = n, c.h = h, c.h2 = h * h, c.invH2 = 1.0f / (h * h), c.m = m;
  c.rho0 = s.restDensity, c.c2 = s.soundSpeed * s.soundSpeed;
  c.background = background;
  c.norm6 = kPoly6 / (h * h * h);
  // The search radius: h and a hair, so that round-off in the run clipping loses no pair.
  c.search = h * (1.0f + 1e-5f);
  c.kp = 0.5f * m * (kSpiky / (h * h * h * h)) / (h * h);
  c.kv = s.viscosity * m * (kVisc / (h * h * h * h * h)) / h;
  c.hasPlants = hasPlants;
  c.dmin = s.domainMin, c.dmax = s.domainMax;
  for (int k = 0; k < 3; ++k) {
    c.wallMin[k] = s.closed(2 * k) ? c.dmin[k] : -kInf;
    c.wallMax[k] = s.closed(2 * k + 1) ? c.dmax[k] : kInf;
    c.closed = c.closed || s.closed(2 * k) || s.closed(2 * k + 1);
  }
  c.volume = m / s.restDensity, c.invRho0 = 1.0f / s.restDensity;
  c.spikyH = kSpiky / (h * h * h * h * h * h);
  c.rmin = 0.25f * s.spacing;
  c.tension = s.allClosed() ? s.backgroundPressure : 0.0f;
  return c;
}

// Particle k moved `moved` metres to x: its obstacle distance bound shrinks by 1.75 times that;
// below h the distance is asked where it is now (as querySdf), and a particle closer than rmin
// is pushed out with its velocity into the obstacle removed.
template <class Grid>
void obstacleAfterMove(Grid& g, const env::Environment& env, size_t k, float moved, float h, float rmin, Vec3& x,
                       Vec3& v) {
  g.budget[k] -= kSdfLipschitz * moved;
  if (!(g.budget[k] < h)) return;
  Vec3 nrm;
  const float d = env.signedDistance(x, &nrm);
  g.budget[k] = d;
  const bool near = d < h && nrm.squaredNorm() > 0.0f;
  g.sdf[k] = near ? d : kInf;
  g.sdfNormal[k] = near ? nrm : Vec3::Zero();
  if (g.sdf[k] < rmin) {
    x += (rmin - g.sdf[k]) * nrm;
    const float vn = v.dot(nrm);
    if (vn < 0.0f) v -= vn * nrm;
    g.sdf[k] = rmin;
    g.budget[k] = rmin;
  }
}

// A substep's first passes in both solvers: the density (with the neighbour search), then the
// plants', then the pair counts. The position-based solver keeps the plants' density and
// gradient for the whole substep and sizes each block's |∇W|/r store to its lists.
template <bool PositionBased, class Grid, class Walls, class Plants>
void densityAndPlantPasses(Grid& g, const Walls& W, const Plants& P, const PassConstants& c, size_t blocks,
                           [[maybe_unused]] bool avx2, SphTimings& timings) {
  {
    ScopedTimer t(&timings.density);
    parallelFor(0, blocks, [&](size_t block) {
#if TENDRIL_SPH_AVX2
      if (avx2) densityAvx2(g, W, c, block);
      else
#endif
        densityGeneric(g, W, c, block);
      if constexpr (PositionBased) g.pairBlocks[block].resize(g.nbrBlocks[block].size());  // lists' length and padding
    }, 1);
  }
  {
    ScopedTimer t(&timings.coupling);
    parallelFor(0, blocks, [&](size_t block) {
#if TENDRIL_SPH_AVX2
      if (avx2) return plantAvx2<PositionBased>(g, P, c, block);
#endif
      plantGeneric<PositionBased>(g, P, c, block);
    }, 1);
  }
  const size_t n = g.size();
  timings.particles += n;
  for (size_t k = 0; k < n; ++k) timings.airPairs += g.nbrCount[k], timings.plantPairs += g.hitCount[k];
}

}  // namespace

void SphAir::substep(const env::Environment& env, float dt) {
  Grid& g = *grid_;
  const Plants& P = *plants_;
  const Walls& W = *walls_;
  const size_t n = g.size(), blocks = (n + kBlock - 1) / kBlock;
  const PassConstants c = passConstants(settings_, n, h_, mass_, backgroundPressure(), P.size() > 0);
  g.nbrBlocks.resize(blocks);
  g.nbrBegin.resize(n), g.nbrCount.resize(n), g.hitCount.resize(n);
  g.invRho.resize(n), g.pOverRho.resize(n), g.packedX.resize(n), g.packedV.resize(n), g.plantAcc.resize(n);
  const bool avx2 = useAvx2();

  densityAndPlantPasses<false>(g, W, P, c, blocks, avx2, timings_);

  {
    ScopedTimer t(&timings_.forces);
    parallelForRange(0, n, [&](size_t begin, size_t end) {
#if TENDRIL_SPH_AVX2
      if (avx2) return forcesAvx2(g, W, c, begin, end);
#endif
      forcesGeneric(g, W, c, begin, end);
    }, kGrain);
  }
  move(env, dt, true);
}

// Moves the particles by their velocities (accelerate: after symplectic Euler's kick by the
// substep's forces and the plants' implicit drag), then the domain and the obstacles, in the
// grid's arrays; each particle's new cell for the re-sort.
void SphAir::move(const env::Environment& env, float dt, bool accelerate) {
  Grid& g = *grid_;
  const size_t n = g.size();
  const PassConstants c = passConstants(settings_, n, h_, mass_, 0.0f, plants_->size() > 0);
  const bool hasPlants = c.hasPlants, closed = c.closed;
  const float h = h_, vmax = settings_.soundSpeed, rmin = c.rmin;
  const Vec3 dmin = c.dmin, dmax = c.dmax, wallMin = c.wallMin, wallMax = c.wallMax;
  ScopedTimer t(&timings_.obstacles);
  const bool hasObstacles = env.obstacleCount() > 0;
  g.cell.resize(n);
  parallelFor(0, n, [&](size_t k) {
    Vec3 v(g.vx[k], g.vy[k], g.vz[k]);
    if (accelerate) {
      v += dt * g.acc[k];
      if (hasPlants) v += dt * g.dragAcc[k] / (1.0f + dt * g.dragRate[k]);  // implicit in the drag
      // A weakly compressible model means nothing past the speed of sound; a safeguard.
      const float speed = v.norm();
      if (speed > vmax) v *= vmax / speed;
    }
    const Vec3 x0(g.px[k], g.py[k], g.pz[k]);
    Vec3 x = x0 + dt * v;
    bool dead = false;
    // Closed faces hold the particle s/4 inside; past an open one it is gone.
    if (closed) {
      for (int c = 0; c < 3; ++c) {
        if (x[c] < wallMin[c] + rmin) x[c] = wallMin[c] + rmin, v[c] = std::max(v[c], 0.0f);
        if (x[c] > wallMax[c] - rmin) x[c] = wallMax[c] - rmin, v[c] = std::min(v[c], 0.0f);
      }
    }
    if ((x.array() < dmin.array()).any() || (x.array() > dmax.array()).any()) {
      dead = true;
      dead_[g.order[k]] = 1;
    }
    if (hasObstacles) obstacleAfterMove(g, env, k, (x - x0).norm(), h, rmin, x, v);
    g.px[k] = x.x(), g.py[k] = x.y(), g.pz[k] = x.z();
    g.vx[k] = v.x(), g.vy[k] = v.y(), g.vz[k] = v.z();
    if (dead) {
      g.cell[k] = kDead;
    } else {
      const Eigen::Vector3i c = g.cellCoord(x);
      g.cell[k] = g.cellIndex(c.x(), c.y(), c.z());
    }
  }, kGrain);
}

// A substep of the position-based solver (PBF, Macklin & Müller 2013, Algorithm 1): move by
// the velocity (prediction), re-sort and search the neighbours there, project the density
// constraint `iterations` times (lambdaRange, deltaRange), then the velocity from the total
// move, MCG03's viscosity (eq. 11's μ∇²v) and the plants' implicit drag on it, and the
// obstacles asked again where the projections moved a particle near one. The air's pressure
// is the constraint's multiplier: a projection λ ∇C is Δt² times the pressure acceleration
// −∇p/ρ, so p_i = −ρ_i Σ λ_i / Δt² (kept per particle: the plants feel the last substep's
// at the start of the next frame, as the weakly compressible air's at the frame's start).
void SphAir::substepPositionBased(const env::Environment& env, float dt) {
  move(env, dt, false);
  {
    ScopedTimer t(&timings_.neighbours);
    regrid();
  }
  Grid& g = *grid_;
  const Plants& P = *plants_;
  const Walls& W = *walls_;
  const size_t n = g.size(), blocks = (n + kBlock - 1) / kBlock;
  PassConstants c = passConstants(settings_, n, h_, mass_, 0.0f, P.size() > 0);
  c.eps = pbfEps_, c.corr = pbfCorr_, c.invWq = pbfInvWq_;
  g.nbrBlocks.resize(blocks), g.pairBlocks.resize(blocks);
  g.nbrBegin.resize(n), g.nbrCount.resize(n), g.hitCount.resize(n);
  g.invRho.resize(n), g.pOverRho.resize(n), g.packedX.resize(n), g.packedX2.resize(n), g.packedV.resize(n);
  g.plantRho.resize(n), g.plantGrad.resize(n), g.extGrad.resize(n);
  g.lambdaSum.assign(n, 0.0f), g.shift.assign(n, Vec3::Zero());
  const bool avx2 = useAvx2();
  densityAndPlantPasses<true>(g, W, P, c, blocks, avx2, timings_);

  const float invDt = 1.0f / dt;
  {
    ScopedTimer t(&timings_.forces);
    parallelFor(0, n, [&](size_t k) { g.packedX[k] = V4f{g.px[k], g.py[k], g.pz[k], 0.0f}; }, 2048);
    for (int it = 0; it < settings_.iterations; ++it) {
      parallelForRange(0, n, [&](size_t begin, size_t end) {
#if TENDRIL_SPH_AVX2
        if (avx2) return lambdaAvx2(g, W, c, begin, end);
#endif
        lambdaGeneric(g, W, c, begin, end);
      }, kGrain);
      parallelForRange(0, n, [&](size_t begin, size_t end) {
#if TENDRIL_SPH_AVX2
        if (avx2) return deltaAvx2(g, c, begin, end);
#endif
        deltaGeneric(g, c, begin, end);
      }, kGrain);
    }
    // The velocity from the whole move; viscosity as in the weakly compressible forces (no
    // pressure, walls or plants' push there: packedV's p/ρ and `pressure` are 0).
    parallelFor(0, n, [&](size_t k) {
      const V4f x = g.packedX[k];
      g.px[k] = x[0], g.py[k] = x[1], g.pz[k] = x[2];
      g.vx[k] += g.shift[k].x() * invDt, g.vy[k] += g.shift[k].y() * invDt, g.vz[k] += g.shift[k].z() * invDt;
      g.invRho[k] = 1.0f / g.rho[k];
      g.packedX[k] = V4f{x[0], x[1], x[2], g.invRho[k]};
      g.packedV[k] = V4f{g.vx[k], g.vy[k], g.vz[k], 0.0f};
      g.pressure[k] = 0.0f;
    }, 2048);
    PassConstants viscous = c;
    viscous.closed = false, viscous.hasPlants = false;
    parallelForRange(0, n, [&](size_t begin, size_t end) {
#if TENDRIL_SPH_AVX2
      if (avx2) return forcesAvx2(g, W, viscous, begin, end);
#endif
      forcesGeneric(g, W, viscous, begin, end);
    }, kGrain);
  }

  ScopedTimer t(&timings_.obstacles);
  const bool hasPlants = c.hasPlants, hasObstacles = env.obstacleCount() > 0;
  const float h = h_, vmax = settings_.soundSpeed, rmin = c.rmin, pressureScale = -invDt * invDt;
  const Vec3 dmin = c.dmin, dmax = c.dmax;
  parallelFor(0, n, [&](size_t k) {
    Vec3 v(g.vx[k], g.vy[k], g.vz[k]);
    v += dt * g.acc[k];
    if (hasPlants) v += dt * g.dragAcc[k] / (1.0f + dt * g.dragRate[k]);  // implicit in the drag
    const float speed = v.norm();
    if (speed > vmax) v *= vmax / speed;  // a safeguard, as in the weakly compressible solver
    Vec3 x(g.px[k], g.py[k], g.pz[k]);
    // Projections may carry a particle out through an open face: gone, as in move().
    if ((x.array() < dmin.array()).any() || (x.array() > dmax.array()).any()) dead_[g.order[k]] = 1;
    if (hasObstacles) obstacleAfterMove(g, env, k, g.shift[k].norm(), h, rmin, x, v);
    g.px[k] = x.x(), g.py[k] = x.y(), g.pz[k] = x.z();
    g.vx[k] = v.x(), g.vy[k] = v.y(), g.vz[k] = v.z();
    g.pressure[k] = pressureScale * g.rho[k] * g.lambdaSum[k];
  }, kGrain);
}

namespace detail {

bool avx2Kernels() { return useAvx2(); }
void forceBaselineKernels(bool on) { gGenericKernels.store(on, std::memory_order_relaxed); }

}  // namespace detail

}  // namespace tendril::wind

// Internals of the SPH air shared by sph.cpp (set-up, emitters, the neighbour grid, the frame)
// and sph_passes.cpp (the plant coupling and the solvers' passes): vector helpers, constants and
// the grid, plant and wall structures. Not a public header.
#pragma once

#include "tendril/wind/sph.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace tendril::wind {

namespace {


constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kDead = std::numeric_limits<uint32_t>::max();
constexpr size_t kMaxCells = size_t(1) << 25;  // uniform-grid cells (128 MiB of cell starts)
constexpr size_t kGrain = 256;
constexpr size_t kBlock = 256;  // particles per neighbour-list block

// Unit-support kernel constants (multiply by 1/h³, 1/h⁴, 1/h⁵ as noted above).
constexpr float kPoly6 = 315.0f / (64.0f * kPi);
constexpr float kSpiky = 45.0f / kPi;
constexpr float kVisc = 45.0f / kPi;

// The SDF sampled by trilinear interpolation may change faster than the true distance
// (up to √3 along a cell diagonal): a particle's known distance bound shrinks by this much
// per metre moved.
constexpr float kSdfLipschitz = 1.75f;

// Four floats or ints: GCC (12 or later, for __builtin_shufflevector) and Clang vector
// extensions, SSE on x86-64 and NEON on ARM.
using V4f = float __attribute__((vector_size(16)));
using V4i = int32_t __attribute__((vector_size(16)));
inline V4f sqrt4(V4f v) {
#if defined(__SSE__)
  return (V4f)_mm_sqrt_ps((__m128)v);
#else
  return V4f{std::sqrt(v[0]), std::sqrt(v[1]), std::sqrt(v[2]), std::sqrt(v[3])};
#endif
}

// The substep's passes are also compiled for AVX2 and chosen at run time (GCC and Clang on
// x86-64, unless the whole build already targets AVX2).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__AVX2__)
#define TENDRIL_SPH_AVX2 1
#else
#define TENDRIL_SPH_AVX2 0
#endif
// The eight-lane helpers are always inlined (at -O0 too), so no call passes an eight-lane vector
// between the AVX2 versions and baseline code, whose ABIs for it differ; GCC's note about that
// does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
#define TENDRIL_INLINE8 [[gnu::always_inline]] inline

// Eight floats or ints: one AVX register where the target has AVX, two SSE registers
// otherwise (the same operations in the same order, so the same results either way).
using V8f = float __attribute__((vector_size(32)));
using V8i = int32_t __attribute__((vector_size(32)));
constexpr V8i kLanes8 = {0, 1, 2, 3, 4, 5, 6, 7};
TENDRIL_INLINE8 V8f splat8(float v) { return V8f{v, v, v, v, v, v, v, v}; }
TENDRIL_INLINE8 V8f join(V4f lo, V4f hi) { return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7); }
TENDRIL_INLINE8 V4f lowHalf(V8f v) { return __builtin_shufflevector(v, v, 0, 1, 2, 3); }
TENDRIL_INLINE8 V4f highHalf(V8f v) { return __builtin_shufflevector(v, v, 4, 5, 6, 7); }
TENDRIL_INLINE8 V4i lowHalf(V8i v) { return __builtin_shufflevector(v, v, 0, 1, 2, 3); }
TENDRIL_INLINE8 V4i highHalf(V8i v) { return __builtin_shufflevector(v, v, 4, 5, 6, 7); }
TENDRIL_INLINE8 V8f masked8(V8i mask, V8f v) { return (V8f)(mask & (V8i)v); }
TENDRIL_INLINE8 V8f load8(const float* p) {
  V8f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// Rows base[j[0]], …, base[j[7]] (four floats each) to four columns of eight: column c, lane l
// = base[j[l]][c]. Rows l and l + 4 share a 128-bit half, so the transpose stays within halves
// (AVX's in-lane unpacks and shuffles).
TENDRIL_INLINE8 void transpose8(const V4f* base, const uint32_t* j, V8f* x, V8f* y, V8f* z, V8f* w) {
  const V8f a = join(base[j[0]], base[j[4]]), b = join(base[j[1]], base[j[5]]);
  const V8f c = join(base[j[2]], base[j[6]]), d = join(base[j[3]], base[j[7]]);
  const V8f t0 = __builtin_shufflevector(a, b, 0, 8, 1, 9, 4, 12, 5, 13);
  const V8f t1 = __builtin_shufflevector(c, d, 0, 8, 1, 9, 4, 12, 5, 13);
  const V8f t2 = __builtin_shufflevector(a, b, 2, 10, 3, 11, 6, 14, 7, 15);
  const V8f t3 = __builtin_shufflevector(c, d, 2, 10, 3, 11, 6, 14, 7, 15);
  *x = __builtin_shufflevector(t0, t1, 0, 1, 8, 9, 4, 5, 12, 13);
  *y = __builtin_shufflevector(t0, t1, 2, 3, 10, 11, 6, 7, 14, 15);
  *z = __builtin_shufflevector(t2, t3, 0, 1, 8, 9, 4, 5, 12, 13);
  *w = __builtin_shufflevector(t2, t3, 2, 3, 10, 11, 6, 7, 14, 15);
}
TENDRIL_INLINE8 V8f sqrt8(V8f v) { return join(sqrt4(lowHalf(v)), sqrt4(highHalf(v))); }
// The sum of the eight lanes in a fixed order.
TENDRIL_INLINE8 float total8(V8f v) {
  const V4f s = lowHalf(v) + highHalf(v);
  return (s[0] + s[1]) + (s[2] + s[3]);
}

// Bit l set where lane l of the mask is set.
inline unsigned movemask(V4i m) {
#if defined(__SSE__)
  return unsigned(_mm_movemask_ps((__m128)m));
#else
  return unsigned(m[0] & 1) | unsigned(m[1] & 2) | unsigned(m[2] & 4) | unsigned(m[3] & 8);
#endif
}

TENDRIL_INLINE8 unsigned movemask8(V8i m) { return movemask(lowHalf(m)) | (movemask(highHalf(m)) << 4); }

// Per 4-bit mask: the numbers of its set lanes, first to last (the rest 0), and how many.
struct LaneTable {
  alignas(16) int32_t lanes[16][4];
  uint8_t count[16];
};
constexpr LaneTable makeLaneTable() {
  LaneTable t{};
  for (unsigned mask = 0; mask < 16; ++mask) {
    int n = 0;
    for (int l = 0; l < 4; ++l)
      if (mask & (1u << l)) t.lanes[mask][n++] = l;
    t.count[mask] = uint8_t(n);
  }
  return t;
}
constexpr LaneTable kLaneTable = makeLaneTable();

// See detail::appendLanes: one table load, one add and one unaligned store, no branch.
inline uint32_t appendLanes(unsigned mask, uint32_t base, uint32_t* out) {
  V4i lanes;
  std::memcpy(&lanes, kLaneTable.lanes[mask], sizeof lanes);
  const int32_t b = int32_t(base);
  lanes += V4i{b, b, b, b};
  std::memcpy(out, &lanes, sizeof lanes);
  return kLaneTable.count[mask];
}

// A row of cells along one axis in cell units: where a point lies (c = (x − origin)/edge) and
// the last cell. A half-width is widened by a hair — a millionth of it and of |x| + |origin|,
// some sixteen times float round-off — so that the round-off of x − origin and of the
// products in cell units never puts a point just inside it into a cell outside its span.
struct RowFrame {
  float c, widen, last, hair;
};
inline RowFrame rowFrame(float x, float origin, float inv, int cells) {
  return {(x - origin) * inv, inv * (1.0f + 1e-6f), float(cells - 1), (std::abs(x) + std::abs(origin)) * 1e-6f * inv};
}
// See detail::rowCells. Clamped before the conversion, so truncation is the floor (and points
// outside the row's ends fall into its outermost cells, as the grid bins them).
inline detail::CellSpan rowSpan(const RowFrame& f, float halfWidth) {
  const float w = halfWidth * f.widen + f.hair;
  return {uint32_t(std::clamp(f.c - w, 0.0f, f.last)), uint32_t(std::clamp(f.c + w, 0.0f, f.last))};
}
}  // namespace

// A uniform grid over the domain, cells of h/8 along x and h across (h/4 or h/2 along x, or
// cubes of h, when that would be too many cells): the particles' state copied into grid order
// (structure of arrays) at the start of a frame and re-sorted by counting sort after every
// substep (regrid), so that a particle's neighbours lie in contiguous runs (one per row of x-adjacent cells), each run
// clipped to the sphere of radius h around it.
struct SphAir::Grid {
  Vec3 origin = Vec3::Zero();
  Vec3 edge = Vec3::Ones(), inv = Vec3::Ones();  // cell edges, their inverses
  Eigen::Vector3i dims = Eigen::Vector3i::Ones();
  std::vector<uint32_t> cellOf;  // per particle (kDead: not in the grid)
  std::vector<uint32_t> start;   // per cell + 1
  std::vector<uint32_t> order;   // grid index → particle index
  // Grid-ordered copies. Within a frame the substeps keep the state here (positions,
  // velocities, densities and obstacle distances move with the particle when the grid is
  // re-sorted), and it goes back to the particles' arrays at the end of the frame.
  std::vector<float> px, py, pz, vx, vy, vz, rho, pressure, sdf;
  std::vector<float> budget;     // sdfBudget_ of the particle
  std::vector<uint32_t> cell;    // the cell after the substep's move (kDead: left the domain)
  // The re-sort's scratch: the next order's arrays, swapped in.
  std::vector<uint32_t> perm, next, order2;
  std::vector<float> px2, py2, pz2, vx2, vy2, vz2, rho2, sdf2, budget2;
  std::vector<Vec3> sdfNormal2;
  std::vector<float> invRho, pOverRho;  // 1/ρ and p/ρ, from the equation of state
  // The same packed per particle for the forces' gathers: (x, y, z, 1/ρ), (v, p/ρ).
  std::vector<V4f> packedX, packedV;
  std::vector<Vec3> sdfNormal;
  // Grid-ordered results of a substep.
  std::vector<Vec3> acc, plantAcc, dragAcc;  // all forces; the plants' pressure push; their drag
  std::vector<float> dragRate;  // Σ φ k / m (1/s): the implicit factor of the drag
  // Per substep, gathered in the density pass and reused by the forces: the air neighbours
  // (0 < r < h, grid order), stored per block of kBlock particles (a fixed split of the grid
  // order, whatever the thread count), each particle's entries contiguous in its block's
  // buffer. And how many plant particles' supports hold the particle (for the benchmark).
  std::vector<std::vector<uint32_t>> nbrBlocks;
  std::vector<uint32_t> nbrBegin, nbrCount, hitCount;
  // The position-based solver's (SphSolver::PositionBased) per substep: the constraint's
  // multiplier λ's sum over the iterations, how far the projections moved the particle,
  // the plants' density and constraint gradient (fixed over a substep: the plants do not move
  // and the air moves a fraction of their support), the walls' and plants' part of ∇C,
  // |∇W_ij|/r per listed neighbour (the λ pass's, for the projection at the same positions)
  // and (x, y, z, λ) as the λ pass writes it for the projection (which writes packedX).
  std::vector<float> lambdaSum, plantRho;
  std::vector<std::vector<float>> pairBlocks;  // as nbrBlocks
  std::vector<Vec3> shift, plantGrad, extGrad;
  std::vector<V4f> packedX2;

  size_t size() const { return order.size(); }
  int cellAxis(float v, int k) const { return std::clamp(int(std::floor((v - origin[k]) * inv[k])), 0, dims[k] - 1); }
  Eigen::Vector3i cellCoord(const Vec3& p) const {
    return Eigen::Vector3i(cellAxis(p.x(), 0), cellAxis(p.y(), 1), cellAxis(p.z(), 2));
  }
  uint32_t cellIndex(int x, int y, int z) const { return uint32_t((size_t(z) * dims.y() + y) * dims.x() + x); }
  // The gap between v and the slab of cell c along axis k (0 inside it); the outermost cells
  // reach to infinity, as particles outside the domain are binned into them.
  float gap(float v, int k, int c) const {
    const float lo = origin[k] + float(c) * edge[k];
    if (c > 0 && v < lo) return lo - v;
    if (c < dims[k] - 1 && v > lo + edge[k]) return v - (lo + edge[k]);
    return 0.0f;
  }
  // Calls f(begin, end) for runs holding every particle closer than r to (x, y, z): the rows of
  // cells the sphere meets, each clipped to the cells along x the sphere meets. A row whose
  // nearest point lies gap_y, gap_z away holds the sphere's points with |x' − x| < √rem,
  // rem = r² − gap_y² − gap_z²: its run is the cells of x ± √rem, found by arithmetic (rowSpan),
  // not by a search along the row.
  template <class F>
  void forSphereRuns(float x, float y, float z, float r, F&& f) const {
    constexpr int kMax = 8;  // cells across are h: 2r ≤ 2 (1 + 1e-5) edges, at most 4 cells
    const float r2 = r * r;
    int lo[3], n[3];
    float g2[3][kMax];
    const float p[3] = {x, y, z};
    for (int k = 1; k < 3; ++k) {
      lo[k] = cellAxis(p[k] - r, k);
      n[k] = std::min(cellAxis(p[k] + r, k) - lo[k] + 1, kMax);
      for (int c = 0; c < n[k]; ++c) {
        const float d = gap(p[k], k, lo[k] + c);
        g2[k][c] = d * d;
      }
    }
    const RowFrame frame = rowFrame(x, origin.x(), inv.x(), dims.x());
    for (int cz = 0; cz < n[2]; ++cz) {
      const float rz = r2 - g2[2][cz];
      if (!(rz > 0.0f)) continue;
      for (int cy = 0; cy < n[1]; ++cy) {
        const float rem = rz - g2[1][cy];
        if (!(rem > 0.0f)) continue;
        const detail::CellSpan span = rowSpan(frame, std::sqrt(rem));
        const uint32_t row = cellIndex(0, lo[1] + cy, lo[2] + cz);
        const uint32_t b = start[row + span.first], e = start[row + span.last + 1];
        if (b < e) f(b, e);
      }
    }
  }
};

// Grown branch particles of the plants that can reach the air, in the order of their cells,
// with what the coupling needs, and binned for the air: every bin (a cubic cell of h/2 over the
// domain) lists the plant particles whose support's bounding box meets it (built once per
// frame: the plants do not move within a frame), so an air particle's candidates are its own
// bin's list.
struct SphAir::Plants {
  std::vector<uint32_t> slot;  // the body's slot in its system's arrays (models::AirBodies)
  std::vector<uint32_t> body;  // which coupled system it belongs to
  std::vector<Vec3> x, axis, v;
  std::vector<float> invA2, invB2;  // 1/α², 1/β²: the support ellipsoid's semi-axes (eq. 13)
  std::vector<float> detG;          // det G = 1/(α β²)
  std::vector<float> volume;        // Ψ = 4/3 π a b² (m³)
  std::vector<float> dragK;         // k = ½ ρ C_d A |u⊥| (kg/s), fixed over a frame
  std::vector<float> invZ;          // 1 / max(Σ V W, ½), fixed over a frame
  std::vector<Vec3> extent;         // half-extents of the support's bounding box
  // The same packed for the plant pass's gathers: (x, 1/α²), (axis, 1/β²), (v, det G k/max(Z, ½)), and
  // Ψ det G (the factors always met together, folded).
  std::vector<V4f> packX, packAxis, packV;
  std::vector<float> psiG;
  // Bins over the domain (cubic cells; the outermost reach to infinity).
  Vec3 origin = Vec3::Zero();
  float edge = 1.0f, inv = 1.0f;
  Eigen::Vector3i dims = Eigen::Vector3i::Ones();
  std::vector<uint32_t> start;      // per bin + 1
  std::vector<uint32_t> entries;    // plant indices per bin, and eight 0s (for 8-wide reads past the last)

  uint32_t binOf(const Vec3& p) const {
    int c[3];
    for (int k = 0; k < 3; ++k) c[k] = std::clamp(int(std::floor((p[k] - origin[k]) * inv)), 0, dims[k] - 1);
    return binIndex(c[0], c[1], c[2]);
  }
  uint32_t binIndex(int x, int y, int z) const { return uint32_t((size_t(z) * dims.y() + y) * dims.x() + x); }

  size_t size() const { return slot.size(); }
  void clear() {
    slot.clear(), body.clear(), x.clear(), axis.clear(), v.clear(), invA2.clear(), invB2.clear(), detG.clear();
    volume.clear(), dragK.clear(), invZ.clear(), extent.clear(), start.clear();  // entries: overwritten
    packX.clear(), packAxis.clear(), packV.clear(), psiG.clear();
  }
};

// Walls as mirrored rest lattices: a wall at distance d adds to a particle's density what the
// fluid's own lattice would add if it continued past the wall (ρ_w(d)), and pushes it by the
// pressure those mirror particles would exert (MCG03's symmetric pressure force with the
// particle's own pressure on both sides: a = −p/(ρ0 ρ) · g_w(d) n). Tabulated over d ∈ [0, h]
// from the same lattice the particle mass is calibrated on, so a lattice of rest spacing next
// to a flat wall has exactly the rest density.
struct SphAir::Walls {
  static constexpr int kSamples = 512;
  float h = 1, step = 1;
  std::vector<float> density, gradient;  // ρ_w(d) (kg/m³), g_w(d) = n·m Σ ∇W_spiky (kg/m⁴, < 0)

  float lookup(const std::vector<float>& t, float d) const {
    if (!(d < h)) return 0.0f;
    const float f = std::max(d, 0.0f) / step;
    const int i = std::min(int(f), kSamples - 2);
    const float w = f - float(i);
    return t[i] + w * (t[i + 1] - t[i]);
  }

  // Where two closed faces meet (the box's edges) both mirrored lattices hold the quadrant
  // beyond both faces: it is subtracted once (inclusion–exclusion; the octant beyond three
  // faces, under 0.5% of ρ0 at h = 2s, is left out). Tabulated over (d1, d2) ∈ [0, h]².
  static constexpr int kEdgeSamples = 64;
  float edgeStep = 1;
  std::vector<float> edgeDensity, edgeGradient;  // ρ_q(d1, d2); n1 · m Σ ∇W_spiky (n2 part: swap)

  float edgeLookup(const std::vector<float>& t, float d1, float d2) const {
    if (!(d1 < h) || !(d2 < h)) return 0.0f;
    const float f1 = std::max(d1, 0.0f) / edgeStep, f2 = std::max(d2, 0.0f) / edgeStep;
    const int i = std::min(int(f1), kEdgeSamples - 2), j = std::min(int(f2), kEdgeSamples - 2);
    const float u = f1 - float(i), v = f2 - float(j);
    auto at = [&](int a, int b) { return t[size_t(a) * kEdgeSamples + b]; };
    return (1 - u) * ((1 - v) * at(i, j) + v * at(i, j + 1)) + u * ((1 - v) * at(i + 1, j) + v * at(i + 1, j + 1));
  }
};

namespace {

// The mirrored lattices of the domain box's six faces at the distances lo = p − min and
// hi = max − p, the quadrants beyond two faces counted once (inclusion–exclusion).
template <class Walls>
float boxGhostDensity(const Walls& W, const Vec3& lo, const Vec3& hi) {
  float rho = 0.0f;
  for (int a = 0; a < 3; ++a) {
    if (!(lo[a] < W.h) && !(hi[a] < W.h)) continue;
    rho += W.lookup(W.density, lo[a]) + W.lookup(W.density, hi[a]);
    for (int b = a + 1; b < 3; ++b)
      rho -= W.edgeLookup(W.edgeDensity, lo[a], lo[b]) + W.edgeLookup(W.edgeDensity, lo[a], hi[b]) +
             W.edgeLookup(W.edgeDensity, hi[a], lo[b]) + W.edgeLookup(W.edgeDensity, hi[a], hi[b]);
  }
  return rho;
}

// Their g_w(d) n summed (the quadrants' share subtracted along each face's normal).
template <class Walls>
Vec3 boxGhostGradient(const Walls& W, const Vec3& lo, const Vec3& hi) {
  Vec3 g = Vec3::Zero();
  for (int c = 0; c < 3; ++c) {
    if (!(lo[c] < W.h) && !(hi[c] < W.h)) continue;
    g[c] += W.lookup(W.gradient, lo[c]) - W.lookup(W.gradient, hi[c]);
    for (int e = 0; e < 3; ++e)
      if (e != c)
        g[c] -= W.edgeLookup(W.edgeGradient, lo[c], lo[e]) + W.edgeLookup(W.edgeGradient, lo[c], hi[e]) -
                W.edgeLookup(W.edgeGradient, hi[c], lo[e]) - W.edgeLookup(W.edgeGradient, hi[c], hi[e]);
  }
  return g;
}

}  // namespace

}  // namespace tendril::wind

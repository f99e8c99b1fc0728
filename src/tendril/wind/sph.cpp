// SPH air, two-way coupled with particle plants (seed 000 §5.3). See sph.h and docs/sph.md.
//
// Seed 000's extraction garbles eq. 11–13; they are reconstructed here from the text around
// them and from Müller, Charypar & Gross 2003 (MCG03), whose forces the seed says it uses:
//   eq. 11  a_i = dv_i/dt = (−∇p + μ∇²v)_i / ρ_i
//   eq. 12  A(x) = Σ_j V_j A_j W(η),  V_j = m_j/ρ_j,  η = (x − x_j)/h
//   eq. 13  η = G (x − x_j)  for an ellipsoidal particle j (Owen et al. 1997's tensor G)
// with MCG03's kernels (eq. 20–22 there), written for η = r/h:
//   W_poly6 = 315/(64π h³) (1 − |η|²)³            density
//   ∇W_spiky = −45/(π h⁴) (1 − |η|)² η̂           pressure (MCG03 eq. 10, symmetrised)
//   ∇²W_visc = 45/(π h⁵) (1 − |η|)               viscosity (MCG03 eq. 14)
// and MCG03's equation of state p = k (ρ − ρ0) with k = c², clamped at 0 (no tension).
#include "tendril/wind/sph.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/particles/world.h"

#include <fmt/format.h>
#include <tbb/parallel_reduce.h>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

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

Error settingError(const char* key, const std::string& message) { return Error("SPH settings", key, message); }

void checkFinite(const char* key, float v) {
  if (!std::isfinite(v)) throw settingError(key, fmt::format("must be a finite number, got {}", v));
}

void checkRange(const char* key, float v, float lo, float hi, const char* unit) {
  checkFinite(key, v);
  if (!(v >= lo && v <= hi)) throw settingError(key, fmt::format("must be in [{}, {}] {}, got {}", lo, hi, unit, v));
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
  std::vector<uint32_t> slot;  // particle id in the ParticleWorld
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
    slot.clear(), x.clear(), axis.clear(), v.clear(), invA2.clear(), invB2.clear(), detG.clear();
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

SphAir::SphAir(const SphSettings& settings) : settings_(settings) {
  validate();
  const float s = settings_.spacing;
  h_ = settings_.supportFactor * s;
  grid_ = std::make_unique<Grid>();
  plants_ = std::make_unique<Plants>();
  walls_ = std::make_unique<Walls>();

  // Particle mass: the rest density on an infinite cubic lattice of spacing s (the lattice
  // sum of W_poly6, self included, times m is ρ0).
  const int reach = int(std::ceil(h_ / s));
  const float invH2 = 1.0f / (h_ * h_), norm6 = kPoly6 / (h_ * h_ * h_);
  double lattice = 0.0;
  for (int z = -reach; z <= reach; ++z)
    for (int y = -reach; y <= reach; ++y)
      for (int x = -reach; x <= reach; ++x) {
        const float q = float(x * x + y * y + z * z) * s * s * invH2;
        if (q < 1.0f) lattice += std::pow(1.0 - q, 3.0);
      }
  mass_ = float(settings_.restDensity / (norm6 * lattice));

  // The position-based solver's constants from the same lattice: the constraint's denominator
  // at rest, D = V² Σ |∇W|² (Σ ∇W = 0 there), is its relaxation ε, which halves a projection
  // in the bulk. Jacobi projections overshoot without it — a particle moves for its own
  // constraint and for each neighbour's, which in a uniform compression doubles the step —
  // and still air starts to oscillate within 0.1 s (ε = 0.01 D: 56% density error, the
  // speed clamp reached; 0.3 D and 0.5 D: 4–8% after 2 s). It also sets the artificial
  // pressure's scale, k = 0.1/D at Δq = 0.2 h (PBF eq. 13 and §4).
  {
    const double volume = mass_ / settings_.restDensity, spikyH = kSpiky / std::pow(double(h_), 6.0);
    double sum = 0.0;
    for (int z = -reach; z <= reach; ++z)
      for (int y = -reach; y <= reach; ++y)
        for (int x = -reach; x <= reach; ++x) {
          const double r = std::sqrt(double(x * x + y * y + z * z)) * s;
          if (r <= 0.0 || r >= h_) continue;
          const double g = spikyH * (h_ - r) * (h_ - r);
          sum += g * g;
        }
    const double rest = volume * volume * sum;
    pbfEps_ = float(rest);
    pbfCorr_ = float(0.1 / rest);
    pbfInvWq_ = float(1.0 / std::pow(1.0 - 0.04, 3.0));
  }

  // Wall tables: mirror layers at −(s/2 + k s) behind a wall at 0, the particle at d.
  Walls& w = *walls_;
  w.h = h_;
  w.step = h_ / float(Walls::kSamples - 1);
  w.density.assign(Walls::kSamples, 0.0f);
  w.gradient.assign(Walls::kSamples, 0.0f);
  const double gradNorm = kSpiky / (double(h_) * h_ * h_ * h_);
  for (int t = 0; t < Walls::kSamples; ++t) {
    const double d = double(t) * w.step;
    double rho = 0.0, grad = 0.0;
    for (int k = 0; (d + s * (0.5 + k)) < h_; ++k) {
      const double dz = d + s * (0.5 + k);
      for (int y = -reach; y <= reach; ++y)
        for (int x = -reach; x <= reach; ++x) {
          const double r = std::sqrt(double(x * x + y * y) * s * s + dz * dz);
          if (r >= h_) continue;
          const double q = r * r / (double(h_) * h_);
          rho += std::pow(1.0 - q, 3.0) * norm6;
          const double e = 1.0 - r / h_;
          grad -= gradNorm * e * e * dz / r;  // n · ∇W_spiky, n pointing from the wall to the particle
        }
    }
    w.density[t] = float(mass_ * rho);
    w.gradient[t] = float(mass_ * grad);
  }
  w.edgeStep = h_ / float(Walls::kEdgeSamples - 1);
  w.edgeDensity.assign(size_t(Walls::kEdgeSamples) * Walls::kEdgeSamples, 0.0f);
  w.edgeGradient.assign(size_t(Walls::kEdgeSamples) * Walls::kEdgeSamples, 0.0f);
  for (int t1 = 0; t1 < Walls::kEdgeSamples; ++t1)
    for (int t2 = 0; t2 < Walls::kEdgeSamples; ++t2) {
      const double d1 = double(t1) * w.edgeStep, d2 = double(t2) * w.edgeStep;
      double rho = 0.0, grad = 0.0;
      for (int k1 = 0; (d1 + s * (0.5 + k1)) < h_; ++k1)
        for (int k2 = 0; (d2 + s * (0.5 + k2)) < h_; ++k2) {
          const double a = d1 + s * (0.5 + k1), b = d2 + s * (0.5 + k2);
          for (int x = -reach; x <= reach; ++x) {
            const double r = std::sqrt(a * a + b * b + double(x * x) * s * s);
            if (r >= h_) continue;
            rho += std::pow(1.0 - r * r / (double(h_) * h_), 3.0) * norm6;
            const double e = 1.0 - r / h_;
            grad -= gradNorm * e * e * a / r;
          }
        }
      w.edgeDensity[size_t(t1) * Walls::kEdgeSamples + t2] = float(mass_ * rho);
      w.edgeGradient[size_t(t1) * Walls::kEdgeSamples + t2] = float(mass_ * grad);
    }

  // The grid over the domain: cells of h/8 along x and h across. A particle's candidates are
  // then about 8 runs (3 × 3 rows, the corners clipped) holding 3.2 candidates per neighbour;
  // cells of h/8 × h/2 × h/2 hold 2.0 per neighbour but in 22 runs, and the cost of a run
  // (its clipping, its loop's set-up and exit) outweighs the candidates saved (callgrind: 30%
  // fewer instructions in the density pass, a third less time). The 27 cells of edge h would
  // hold 6.4 per neighbour. Cells of h/4 or h/2 along x, or cubes of h, where the finer ones
  // would be too many.
  Grid& g = *grid_;
  g.origin = settings_.domainMin;
  auto cellsOf = [&](const Vec3& edge, Eigen::Vector3i* dims) {
    size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      (*dims)[k] = std::max(1, int(std::ceil((settings_.domainMax[k] - settings_.domainMin[k]) / edge[k])));
      cells *= size_t((*dims)[k]);
    }
    return cells;
  };
  size_t cells = cellsOf(Vec3::Constant(h_), &g.dims);
  if (cells > kMaxCells)
    throw settingError("domain", fmt::format("the domain holds {} cells of the kernel support h = {} m (at most {}): "
                                             "shrink the domain or raise the spacing",
                                             cells, h_, kMaxCells));
  g.edge = Vec3::Constant(h_);
  for (const float along : {0.125f, 0.25f, 0.5f}) {
    const Vec3 edge(along * h_, h_, h_);
    Eigen::Vector3i dims;
    if (const size_t n = cellsOf(edge, &dims); n <= kMaxCells) {
      g.edge = edge, g.dims = dims, cells = n;
      break;
    }
  }
  g.inv = g.edge.cwiseInverse();
  // The plants' bins: cubic cells of h/2 (or h).
  Plants& P = *plants_;
  P.origin = settings_.domainMin;
  P.edge = h_;
  // The position-based solver's two or three substeps do not repay the finer bins' cost
  // (about five times the entries): cubes of h there (frame 22.8–23.3 → 20.3–21.2 ms in the
  // benchmark, bench/README.md).
  if (Eigen::Vector3i dims; settings_.solver == SphSolver::WeaklyCompressible &&
                            cellsOf(Vec3::Constant(0.5f * h_), &dims) <= kMaxCells)
    P.edge = 0.5f * h_;
  P.inv = 1.0f / P.edge;
  cellsOf(Vec3::Constant(P.edge), &P.dims);
  g.start.assign(cells + 1, 0);
}

SphAir::~SphAir() = default;
SphAir::SphAir(SphAir&&) noexcept = default;
SphAir& SphAir::operator=(SphAir&&) noexcept = default;

void SphAir::validate() const {
  const SphSettings& s = settings_;
  checkRange("restDensity", s.restDensity, 0.01f, 1e4f, "kg/m³");
  checkRange("spacing", s.spacing, 1e-4f, 100.0f, "m");
  checkRange("supportFactor", s.supportFactor, 1.5f, 4.0f, "");
  checkRange("soundSpeed", s.soundSpeed, 0.01f, 1e4f, "m/s");
  checkRange("viscosity", s.viscosity, 0.0f, 1e3f, "Pa·s");
  checkRange("backgroundPressure", s.backgroundPressure, 0.0f, 1.0f, "(share of c²ρ0)");
  checkRange("dragCoefficient", s.dragCoefficient, 0.0f, 10.0f, "");
  checkRange("dt", s.dt, 1e-6f, 1.0f, "s");
  checkRange("cfl", s.cfl, 0.01f, 1.0f, "");
  if (s.iterations < 1 || s.iterations > 50)
    throw settingError("iterations", fmt::format("must be in [1, 50], got {}", s.iterations));
  if (s.maxSubsteps < 1 || s.maxSubsteps > 100000)
    throw settingError("maxSubsteps", fmt::format("must be in [1, 100000], got {}", s.maxSubsteps));
  for (int k = 0; k < 3; ++k) {
    checkFinite("domainMin", s.domainMin[k]);
    checkFinite("domainMax", s.domainMax[k]);
    if (!(s.domainMax[k] - s.domainMin[k] >= s.spacing))
      throw settingError("domainMax", fmt::format("must exceed domainMin by at least the spacing on every axis "
                                                  "(axis {}: {} to {})",
                                                  "xyz"[k], s.domainMin[k], s.domainMax[k]));
  }
  if (s.maxParticles < 1 || s.maxParticles > (size_t(1) << 31))
    throw settingError("maxParticles", fmt::format("must be in [1, 2^31], got {}", s.maxParticles));
}

uint32_t SphAir::addEmitter(const SphEmitter& e) {
  checkEmitter(e);
  SphEmitter copy = e;
  copy.direction.normalize();
  emitters_.push_back(copy);
  emitterClock_.push_back(0.0);
  return uint32_t(emitters_.size() - 1);
}

void SphAir::checkEmitter(const SphEmitter& e) const {
  auto bad = [&](const char* key, const std::string& m) { return Error("SPH emitter", key, m); };
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(e.position[k]) || !std::isfinite(e.direction[k]))
      throw bad("position", "position and direction must be finite");
  if (!(e.direction.norm() > 1e-6f)) throw bad("direction", "must not be zero");
  if (!(e.speed > 0.0f && e.speed < settings_.soundSpeed))
    throw bad("speed", fmt::format("must be in (0, soundSpeed = {}) m/s, got {}", settings_.soundSpeed, e.speed));
  if (!(e.rate >= 0.0f && std::isfinite(e.rate))) throw bad("rate", fmt::format("must be >= 0 particles/s, got {}", e.rate));
  if (!(e.radius > 0.0f && std::isfinite(e.radius))) throw bad("radius", fmt::format("must be > 0 m, got {}", e.radius));
  // A layer is the lattice within the disc's bounding square (emit): keep it to what the air
  // could ever hold.
  const double side = 2.0 * std::floor(double(e.radius) / double(settings_.spacing)) + 1.0;
  const double siteCap = std::max(4.0 * double(settings_.maxParticles), 1e6);
  if (side * side > siteCap)
    throw bad("radius", fmt::format("{} m spans {:.3g} lattice sites of spacing {} m per layer, more than {:.3g} (four "
                                    "times maxParticles): shrink it or raise maxParticles",
                                    e.radius, side * side, settings_.spacing, siteCap));
  const Bounds3 domain{settings_.domainMin, settings_.domainMax};
  if (!domain.contains(e.position))
    throw bad("position", fmt::format("({:.3g}, {:.3g}, {:.3g}) lies outside the SPH domain", e.position.x(),
                                      e.position.y(), e.position.z()));
}

void SphAir::clearEmitters() {
  emitters_.clear();
  emitterClock_.clear();
}

size_t SphAir::addParticle(const Vec3& x, const Vec3& v) {
  x_.push_back(x);
  v_.push_back(v);
  rho_.push_back(settings_.restDensity);
  p_.push_back(0.0f);
  sdfBudget_.push_back(-kInf);  // unknown: queried before the next density pass
  sdf_.push_back(kInf);
  sdfNormal_.push_back(Vec3::Zero());
  dead_.push_back(0);
  return x_.size() - 1;
}

size_t SphAir::fillBox(const Vec3& min, const Vec3& max, const Vec3& velocity) {
  return fill(min, max, nullptr, velocity);
}

size_t SphAir::fillBox(const Vec3& min, const Vec3& max, const env::Environment& env, const Vec3& velocity) {
  return fill(min, max, &env, velocity);
}

size_t SphAir::fill(const Vec3& min, const Vec3& max, const env::Environment* env, const Vec3& velocity) {
  const float s = settings_.spacing;
  const Vec3 lo = min.cwiseMax(settings_.domainMin), hi = max.cwiseMin(settings_.domainMax);
  if (!isFinite(min) || !isFinite(max) || !isFinite(velocity))
    throw Error("SPH fillBox", "", "the box and velocity must be finite");
  Eigen::Vector3i n;
  for (int k = 0; k < 3; ++k) n[k] = int(std::floor((hi[k] - lo[k]) / s + 1e-4f));
  if ((n.array() < 1).any())
    throw Error("SPH fillBox", "",
                fmt::format("the box ({:.3g}, {:.3g}, {:.3g})–({:.3g}, {:.3g}, {:.3g}) holds no lattice site of spacing "
                            "{} m inside the domain",
                            min.x(), min.y(), min.z(), max.x(), max.y(), max.z(), s));
  const size_t sites = size_t(n.x()) * n.y() * n.z();
  if (count() + sites > settings_.maxParticles)
    throw Error("SPH fillBox", "",
                fmt::format("{} more particles would exceed maxParticles = {}: raise it or fill less", sites,
                            settings_.maxParticles));
  // Sites at the cell centres of the box's lattice: s/2 from its faces, where a wall's
  // mirrored lattice continues it.
  std::vector<Vec3> sitesOut(sites);
  std::vector<uint8_t> keep(sites, 1);
  parallelFor(0, sites, [&](size_t i) {
    const int x = int(i % size_t(n.x())), y = int((i / size_t(n.x())) % size_t(n.y())),
              z = int(i / (size_t(n.x()) * n.y()));
    sitesOut[i] = lo + s * Vec3(x + 0.5f, y + 0.5f, z + 0.5f);
    if (env && env->signedDistance(sitesOut[i]) < 0.45f * s) keep[i] = 0;  // s/2, less round-off
  }, 1024);
  size_t added = 0;
  for (size_t i = 0; i < sites; ++i)
    if (keep[i]) addParticle(sitesOut[i], velocity), ++added;
  buildGrid();
  return added;
}

float SphAir::backgroundPressure() const {
  // An open face has no ambient air outside it: a background pressure would blow the air out
  // through it (and speed a stream up by √(2 p_b/ρ0)), so only sealed boxes use one.
  if (!settings_.allClosed()) return 0.0f;
  return settings_.backgroundPressure * settings_.soundSpeed * settings_.soundSpeed * settings_.restDensity;
}

size_t SphAir::coupledPlantParticles() const { return plants_->size(); }

void SphAir::emit(const env::Environment& env) {
  const float s = settings_.spacing;
  // The position-based air cannot be compressed: a site where the air ahead has not moved on
  // (a particle closer than `gap`, in the grid of the frame's last substep) is left out, or the
  // projections would throw the two apart.
  const bool positionBased = settings_.solver == SphSolver::PositionBased;
  const float gap = 0.75f * s;
  const Grid& g = *grid_;
  auto occupied = [&](const Vec3& p, float r) {
    bool found = false;
    g.forSphereRuns(p.x(), p.y(), p.z(), r, [&](uint32_t b, uint32_t e) {
      for (uint32_t k = b; k < e && !found; ++k)
        found = (Vec3(g.px[k], g.py[k], g.pz[k]) - p).squaredNorm() < r * r;
    });
    return found;
  };
  for (size_t k = 0; k < emitters_.size(); ++k) {
    const SphEmitter& e = emitters_[k];
    // A layer: the square lattice of spacing s within the disc.
    const Vec3 u = anyPerpendicular(e.direction), w = e.direction.cross(u);
    const int r = int(std::floor(e.radius / s));
    std::vector<Vec3> layer;
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i)
        if (float(i * i + j * j) * s * s <= e.radius * e.radius) layer.push_back(e.position + s * (float(i) * u + float(j) * w));
    // Layers every s/speed seconds carry the rest density; a given rate spaces them in time.
    const double interval = e.rate > 0.0f ? double(layer.size()) / e.rate : double(s) / e.speed;
    emitterClock_[k] += settings_.dt;
    while (emitterClock_[k] >= interval) {
      emitterClock_[k] -= interval;
      // The layer left the disc `age` seconds before the end of this frame.
      const Vec3 offset = e.direction * float(e.speed * emitterClock_[k]);
      for (const Vec3& site : layer) {
        if (count() >= settings_.maxParticles) {
          if (!warnedCapacity_)
            log::warn("SPH air: {} particles reached maxParticles; emitters pause (raise maxParticles)", count());
          warnedCapacity_ = true;
          return;
        }
        const Vec3 p = site + offset;
        if (!Bounds3{settings_.domainMin, settings_.domainMax}.contains(p)) continue;
        if (env.obstacleCount() > 0 && env.signedDistance(p) < 0.45f * s) continue;
        if (positionBased && occupied(p, gap)) continue;
        addParticle(p, e.direction * e.speed);
      }
    }
  }
}

void SphAir::removeDead() {
  size_t out = 0;
  for (size_t i = 0; i < x_.size(); ++i) {
    if (dead_[i]) continue;
    if (out != i) {
      x_[out] = x_[i], v_[out] = v_[i], rho_[out] = rho_[i], p_[out] = p_[i];
      sdfBudget_[out] = sdfBudget_[i], sdf_[out] = sdf_[i], sdfNormal_[out] = sdfNormal_[i];
      dead_[out] = 0;
    }
    ++out;
  }
  x_.resize(out), v_.resize(out), rho_.resize(out), p_.resize(out), sdfBudget_.resize(out), sdf_.resize(out);
  sdfNormal_.resize(out), dead_.resize(out);
}

void SphAir::buildGrid() {
  Grid& g = *grid_;
  const size_t n = count();
  g.cellOf.resize(n);
  parallelFor(0, n, [&](size_t i) {
    if (dead_[i]) {
      g.cellOf[i] = kDead;
      return;
    }
    const Eigen::Vector3i c = g.cellCoord(x_[i]);
    g.cellOf[i] = g.cellIndex(c.x(), c.y(), c.z());
  }, 2048);
  // Counting sort, stable in particle order: the grid order depends only on the positions.
  std::fill(g.start.begin(), g.start.end(), 0u);
  size_t live = 0;
  for (size_t i = 0; i < n; ++i)
    if (g.cellOf[i] != kDead) ++g.start[g.cellOf[i] + 1], ++live;
  for (size_t c = 1; c < g.start.size(); ++c) g.start[c] += g.start[c - 1];
  g.order.resize(live);
  {
    std::vector<uint32_t> next(g.start.begin(), g.start.end() - 1);
    for (size_t i = 0; i < n; ++i)
      if (g.cellOf[i] != kDead) g.order[next[g.cellOf[i]]++] = uint32_t(i);
  }
  for (auto* a : {&g.sdf, &g.dragRate, &g.budget}) a->resize(live);
  // Padded by eight for 8-wide loads (the padding is masked off).
  for (auto* a : {&g.px, &g.py, &g.pz, &g.vx, &g.vy, &g.vz, &g.rho, &g.pressure}) a->assign(live + 8, 0.0f);
  g.sdfNormal.resize(live), g.acc.resize(live), g.dragAcc.resize(live);
  const float c2 = settings_.soundSpeed * settings_.soundSpeed, rho0 = settings_.restDensity;
  const float background = backgroundPressure();
  const bool positionBased = settings_.solver == SphSolver::PositionBased;
  parallelFor(0, live, [&](size_t k) {
    const uint32_t i = g.order[k];
    g.px[k] = x_[i].x(), g.py[k] = x_[i].y(), g.pz[k] = x_[i].z();
    g.vx[k] = v_[i].x(), g.vy[k] = v_[i].y(), g.vz[k] = v_[i].z();
    g.rho[k] = rho_[i];
    // The position-based solver's pressure comes from its last substep (see substepPositionBased).
    g.pressure[k] = positionBased ? p_[i] : std::max(0.0f, c2 * (rho_[i] - rho0) + background);
    g.sdf[k] = sdf_[i];
    g.sdfNormal[k] = sdfNormal_[i];
    g.budget[k] = sdfBudget_[i];
  }, 2048);
}

// Re-sorts the grid after a substep by the cells its particles moved into (g.cell), stable in
// the current grid order, dropping those that left the domain; every grid-ordered array of the
// state moves with its particle. Particles move a fraction of a cell per substep, so the
// gathers are nearly sequential.
void SphAir::regrid() {
  Grid& g = *grid_;
  const size_t n = g.size();
  std::fill(g.start.begin(), g.start.end(), 0u);
  size_t live = 0;
  for (size_t k = 0; k < n; ++k)
    if (g.cell[k] != kDead) ++g.start[g.cell[k] + 1], ++live;
  for (size_t c = 1; c < g.start.size(); ++c) g.start[c] += g.start[c - 1];
  g.next.assign(g.start.begin(), g.start.end() - 1);
  g.perm.resize(live);
  for (size_t k = 0; k < n; ++k)
    if (g.cell[k] != kDead) g.perm[g.next[g.cell[k]]++] = uint32_t(k);
  // Padded by eight (zeros) like the arrays they replace.
  for (auto* a : {&g.px2, &g.py2, &g.pz2, &g.vx2, &g.vy2, &g.vz2, &g.rho2}) {
    a->resize(live + 8);
    std::fill(a->begin() + ptrdiff_t(live), a->end(), 0.0f);
  }
  g.sdf2.resize(live), g.budget2.resize(live), g.sdfNormal2.resize(live), g.order2.resize(live);
  parallelFor(0, live, [&](size_t k2) {
    const uint32_t k = g.perm[k2];
    g.px2[k2] = g.px[k], g.py2[k2] = g.py[k], g.pz2[k2] = g.pz[k];
    g.vx2[k2] = g.vx[k], g.vy2[k2] = g.vy[k], g.vz2[k2] = g.vz[k];
    g.rho2[k2] = g.rho[k], g.sdf2[k2] = g.sdf[k], g.budget2[k2] = g.budget[k];
    g.sdfNormal2[k2] = g.sdfNormal[k];
    g.order2[k2] = g.order[k];
  }, 2048);
  std::swap(g.px, g.px2), std::swap(g.py, g.py2), std::swap(g.pz, g.pz2);
  std::swap(g.vx, g.vx2), std::swap(g.vy, g.vy2), std::swap(g.vz, g.vz2);
  std::swap(g.rho, g.rho2), std::swap(g.sdf, g.sdf2), std::swap(g.budget, g.budget2);
  std::swap(g.sdfNormal, g.sdfNormal2), std::swap(g.order, g.order2);
  g.pressure.resize(live + 8);
  g.dragRate.resize(live);
  g.acc.resize(live), g.dragAcc.resize(live);
}

// The grid-ordered state back to the particles' arrays (the end of a frame's substeps).
void SphAir::scatterGrid() {
  const Grid& g = *grid_;
  parallelFor(0, g.size(), [&](size_t k) {
    const uint32_t i = g.order[k];
    x_[i] = Vec3(g.px[k], g.py[k], g.pz[k]);
    v_[i] = Vec3(g.vx[k], g.vy[k], g.vz[k]);
    rho_[i] = g.rho[k];
    p_[i] = g.pressure[k];
    sdfBudget_[i] = g.budget[k];
    sdf_[i] = g.sdf[k];
    sdfNormal_[i] = g.sdfNormal[k];
  }, 2048);
}

void SphAir::querySdf(const env::Environment& env, size_t i) {
  Vec3 n;
  const float d = env.signedDistance(x_[i], &n);
  sdfBudget_[i] = d;
  if (d < h_ && n.squaredNorm() > 0.0f) {
    sdf_[i] = d;
    sdfNormal_[i] = n;
  } else {
    sdf_[i] = kInf;
    sdfNormal_[i] = Vec3::Zero();
  }
}

// The plants' grown branch particles that can reach the domain, in the order of their bins,
// and each listed in the bins its support's bounding box meets.
void SphAir::collectPlants(const particles::ParticleWorld& world) {
  Plants& P = *plants_;
  P.clear();
  std::vector<uint32_t> found;
  const Vec3 lo = settings_.domainMin, hi = settings_.domainMax;
  for (uint32_t i = 0; i < world.capacity(); ++i) {
    const uint32_t f = world.flags(i);
    if (!(f & particles::kActive) || !(f & particles::kGrown) || (f & particles::kLeaf)) continue;
    const float reach = world.halfLength(i) + h_;
    const Vec3& x = world.position(i);
    if (!isFinite(x) || ((x.array() < (lo.array() - reach)).any() || (x.array() > (hi.array() + reach)).any())) continue;
    found.push_back(i);
  }
  // Counting sort by the cell of the centre, stable in particle id.
  const size_t n = found.size(), cells = size_t(P.dims.x()) * P.dims.y() * P.dims.z();
  std::vector<uint32_t> cellOf(n), first(cells + 1, 0);
  for (size_t k = 0; k < n; ++k) {
    cellOf[k] = P.binOf(world.position(found[k]));
    ++first[cellOf[k] + 1];
  }
  for (size_t c = 1; c < first.size(); ++c) first[c] += first[c - 1];
  P.slot.resize(n), P.x.resize(n), P.axis.resize(n), P.v.resize(n), P.invA2.resize(n), P.invB2.resize(n);
  P.detG.resize(n), P.volume.resize(n), P.dragK.assign(n, 0.0f), P.invZ.assign(n, 0.0f), P.extent.resize(n);
  P.packX.resize(n), P.packAxis.resize(n), P.psiG.resize(n), P.packV.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const uint32_t j = first[cellOf[k]]++;
    const uint32_t i = found[k];
    const float a = world.halfLength(i), b = world.radius(i);
    // eq. 13: G maps the particle's support ellipsoid — its own ellipsoid grown by the air's
    // support h along every axis — onto the unit ball: G = R diag(1/α, 1/β, 1/β) Rᵀ.
    const float alpha = a + h_, beta = b + h_;
    P.slot[j] = i;
    P.x[j] = world.position(i);
    P.axis[j] = (world.orientation(i) * Vec3::UnitY()).normalized();
    P.v[j] = world.velocity(i);
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
void SphAir::plantSide(particles::ParticleWorld& world) {
  Plants& P = *plants_;
  const Grid& g = *grid_;
  std::vector<Vec3>& external = world.externalAcceleration();
  external.assign(world.capacity(), Vec3::Zero());
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
    // Stem drag in cross-flow: F = ½ ρ C_d (2a · 2b) |u⊥| u⊥, u⊥ the relative air velocity
    // across the axis (the axial part's skin friction is neglected).
    Vec3 rel = gather.velocity * P.invZ[j] - P.v[j];
    rel -= rel.dot(P.axis[j]) * P.axis[j];
    const float area = 4.0f * world.halfLength(i) * world.radius(i);
    P.dragK[j] = 0.5f * rho0 * std::min(z, 1.0f) * cd * area * rel.norm();
    P.packV[j] = V4f{P.v[j].x(), P.v[j].y(), P.v[j].z(), P.detG[j] * P.dragK[j] * P.invZ[j]};
    const float mj = world.mass(i);
    // Implicit in the drag, so a light particle never overshoots the air's velocity.
    external[i] = P.dragK[j] * rel / (mj + P.dragK[j] * dt) + gather.pressureForce / mj;
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

void SphAir::step(const env::Environment& env, particles::ParticleWorld* plants) {
  Timer total;
  timings_ = SphTimings();
  const float h = h_;
  {
    ScopedTimer t(&timings_.obstacles);
    // Everyone when the obstacles changed (or this is another environment); otherwise, and
    // within the frame, only the particles that may have come within h of one. The others'
    // distance is still at least their bound ≥ h, so their sdf_ is +inf, as a query would give:
    // the same distances as asking everyone.
    if (env.obstacleCount() > 0) {
      const bool moved = env.obstacleRevision() != sdfRevision_;
      parallelFor(0, count(), [&](size_t i) {
        if (moved || !(sdfBudget_[i] >= h)) querySdf(env, i);
      }, 1024);
    } else {
      std::fill(sdf_.begin(), sdf_.end(), kInf);
      std::fill(sdfBudget_.begin(), sdfBudget_.end(), kInf);
    }
    sdfRevision_ = env.obstacleRevision();
  }
  {
    ScopedTimer t(&timings_.neighbours);
    buildGrid();
  }
  {
    ScopedTimer t(&timings_.coupling);
    Timer frame;
    if (plants) {
      collectPlants(*plants);
      plantSide(*plants);
    } else {
      plants_->clear();
    }
    timings_.plantFrame = frame.seconds();
  }

  // Substeps: Δt ≤ cfl·h/(c + v_max) (acoustic CFL; the position-based solver's, cfl·h/v_max)
  // and ≤ 0.125 h² ρ0/μ (viscous diffusion).
  const bool positionBased = settings_.solver == SphSolver::PositionBased;
  float vmax = 0.0f;
  for (const SphEmitter& e : emitters_) vmax = std::max(vmax, e.speed);
  vmax = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, count(), 4096), vmax,
      [&](const tbb::blocked_range<size_t>& r, float m) {
        for (size_t i = r.begin(); i != r.end(); ++i) m = std::max(m, v_[i].squaredNorm());
        return m;
      },
      [](float a, float b) { return std::max(a, b); });
  vmax = std::min(std::sqrt(vmax), settings_.soundSpeed);
  float limit = positionBased ? settings_.cfl * h / std::max(vmax, 1e-6f)
                              : settings_.cfl * h / (settings_.soundSpeed + vmax);
  if (settings_.viscosity > 0.0f) limit = std::min(limit, 0.125f * h * h * settings_.restDensity / settings_.viscosity);
  int substeps = int(std::ceil(settings_.dt / limit - 1e-4f));
  if (substeps > settings_.maxSubsteps) {
    if (!warnedSubsteps_)
      log::warn("SPH air: a stable step needs {} substeps, maxSubsteps is {} (raise it, or lower soundSpeed)", substeps,
                settings_.maxSubsteps);
    warnedSubsteps_ = true;
    substeps = settings_.maxSubsteps;
  }
  substeps = std::max(substeps, 1);
  const float dt = settings_.dt / float(substeps);
  for (int s = 0; s < substeps; ++s) {
    if (positionBased) {
      substepPositionBased(env, dt);
      continue;
    }
    substep(env, dt);
    ScopedTimer t(&timings_.neighbours);
    if (s + 1 < substeps) regrid();
  }
  timings_.substeps = substeps;
  {
    ScopedTimer t(&timings_.neighbours);
    scatterGrid();
  }

  emit(env);
  removeDead();
  {
    ScopedTimer t(&timings_.neighbours);
    buildGrid();
  }
  time_ += settings_.dt;
  ++steps_;
  timings_.total = total.seconds();
}

Vec3 SphAir::velocityAt(const Vec3& p) const { return velocityAt(p, nullptr); }

Vec3 SphAir::velocityAt(const Vec3& p, bool* covered) const {
  const Grid& g = *grid_;
  if (covered) *covered = false;
  if (!isFinite(p) || !Bounds3{settings_.domainMin, settings_.domainMax}.contains(p) || g.size() == 0)
    return Vec3::Zero();
  const float invH2 = 1.0f / (h_ * h_), norm6 = kPoly6 / (h_ * h_ * h_);
  float z = 0.0f;
  Vec3 sum = Vec3::Zero();
  g.forSphereRuns(p.x(), p.y(), p.z(), h_ * (1.0f + 1e-5f), [&](uint32_t b, uint32_t e) {
    for (uint32_t k = b; k < e; ++k) {
      const float dx = g.px[k] - p.x(), dy = g.py[k] - p.y(), dz = g.pz[k] - p.z();
      const float t = 1.0f - (dx * dx + dy * dy + dz * dz) * invH2;
      if (!(t > 0.0f)) continue;
      const float w = mass_ / g.rho[k] * norm6 * t * t * t;
      z += w;
      sum += w * Vec3(g.vx[k], g.vy[k], g.vz[k]);
    }
  });
  if (covered) *covered = z > 0.0f;
  return sum / std::max(z, 0.5f);
}

namespace detail {

CellSpan rowCells(float x, float halfWidth, float origin, float edge, int cells) {
  return rowSpan(rowFrame(x, origin, 1.0f / edge, cells), halfWidth);
}

uint32_t appendLanes(unsigned mask, uint32_t base, uint32_t* out) { return wind::appendLanes(mask & 15u, base, out); }


bool avx2Kernels() { return useAvx2(); }
void forceBaselineKernels(bool on) { gGenericKernels.store(on, std::memory_order_relaxed); }

}  // namespace detail

}  // namespace tendril::wind

// SPH air, two-way coupled with plants (seed 000 §5.3): set-up, emitters, the neighbour grid and
// the frame; the coupling and the solvers' passes are in sph_passes.cpp. See sph.h and docs/sph.md.
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
#include "tendril/wind/sph_detail.h"

#include <fmt/format.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tendril::wind {

namespace {

Error settingError(const char* key, const std::string& message) { return Error("SPH settings", key, message); }

void checkFinite(const char* key, float v) {
  if (!std::isfinite(v)) throw settingError(key, fmt::format("must be a finite number, got {}", v));
}

void checkRange(const char* key, float v, float lo, float hi, const char* unit) {
  checkFinite(key, v);
  if (!(v >= lo && v <= hi)) throw settingError(key, fmt::format("must be in [{}, {}] {}, got {}", lo, hi, unit, v));
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
  if (s.kernel != SphKernel::Anisotropic && s.kernel != SphKernel::Isotropic)
    throw settingError("kernel", fmt::format("must be Anisotropic or Isotropic, got {}", int(s.kernel)));
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

void SphAir::step(const env::Environment& env, models::AirCoupling* plants) {
  models::AirCoupling* const one[1] = {plants};
  step(env, plants ? std::span<models::AirCoupling* const>(one) : std::span<models::AirCoupling* const>());
}

void SphAir::step(const env::Environment& env, std::span<models::AirCoupling* const> plants) {
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
    if (!plants.empty()) {
      std::vector<models::AirBodies> bodies;
      for (const models::AirCoupling* system : plants) bodies.push_back(system->airBodies());
      collectPlants(bodies);
      plantSide(plants, bodies);
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

}  // namespace detail

}  // namespace tendril::wind

#include "tendril/env/wind_field.h"

#include "tendril/core/random.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace tendril::env {

bool WindSettings::calm() const {
  if (velocity.squaredNorm() > 0.0f) return false;
  for (const WindEmitter& e : emitters)
    if (e.speed > 0.0f) return false;
  return true;
}

// The noise's value at lattice point (i, j): one mix of the seed and both coordinates, each
// scaled by its own odd constant (the mix's avalanche spreads every input bit).
static float lattice(int64_t i, int64_t j, uint64_t seed) {
  uint64_t h = mix64(seed ^ (uint64_t(i) * 0x9e3779b97f4a7c15ull) ^ (uint64_t(j) * 0xc2b2ae3d27d4eb4full));
  return float(h >> 40) * (2.0f / 16777216.0f) - 1.0f;
}

// The turn noise's seed, from the wind's.
constexpr uint64_t kTurnSeed = 0x5bd1e995ull;

void WindField::prepare() {
  speed_ = settings_.velocity.norm();
  dir_ = speed_ > 0.0f ? Vec3(settings_.velocity / speed_) : Vec3::UnitX();
  const Vec3 across = dir_.cross(Vec3::UnitY());
  acrossIsX_ = !(across.squaredNorm() > 1e-8f);
  across_ = acrossIsX_ ? Vec3::UnitX() : across.normalized();
}

float WindField::noise(float u, float v, uint64_t seed) {
  float fu = std::floor(u), fv = std::floor(v);
  int64_t i = int64_t(fu), j = int64_t(fv);
  float a = quintic(u - fu), b = quintic(v - fv);
  float x0 = lattice(i, j, seed) + a * (lattice(i + 1, j, seed) - lattice(i, j, seed));
  float x1 = lattice(i, j + 1, seed) + a * (lattice(i + 1, j + 1, seed) - lattice(i, j + 1, seed));
  return x0 + b * (x1 - x0);
}

Vec3 WindField::ambient(const Vec3& p, float t) const {
  const WindSettings& s = settings_;
  if (s.mode != WindMode::Gusty) return s.velocity;
  const float speed = speed_;
  if (speed <= 0.0f) return s.velocity;
  // Gust fronts travel downwind with the wind: the noise sees the time a parcel of air left a
  // plane through the origin, and the position across the wind. (GustSampler repeats these
  // steps with the per-point ones kept: keep the two the same.)
  float acrossDist = acrossIsX_ ? p.x() : p.dot(across_);
  float tau = (t - p.dot(dir_) / speed) / s.gustPeriod;
  float sigma = acrossDist / s.gustScale;
  float gust = noise(tau, sigma, s.seed);
  float turn = noise(tau + 101.3f, sigma + 57.1f, s.seed ^ kTurnSeed);
  return gustWind(gust, turn);
}

Vec3 WindField::jet(const WindEmitter& e, const Vec3& p) {
  Vec3 d = p - e.position;
  float along = d.dot(e.direction);
  if (along < 0.0f || along > e.reach || e.speed <= 0.0f) return Vec3::Zero();
  float r = (d - along * e.direction).norm();
  float width = e.radius + along * std::tan(e.spread);
  if (r >= 1.5f * width) return Vec3::Zero();
  // Momentum flux speed² · area is conserved as the jet widens; the edge fades smoothly from
  // the jet's radius to 1.5 times it, and the tip over the last tenth of its reach.
  float speed = e.speed * (e.radius / width);
  float edge = r <= width ? 1.0f : 1.0f - quintic((r - width) / (0.5f * width));
  float tail = along < 0.9f * e.reach ? 1.0f : 1.0f - quintic((along - 0.9f * e.reach) / (0.1f * e.reach));
  return speed * edge * tail * e.direction;
}

Vec3 WindField::sample(const Vec3& p, float t) const {
  if (settings_.mode == WindMode::Sph && air_) {
    bool covered = false;
    Vec3 v = air_->velocityAt(p, &covered);
    if (covered) return v;
  }
  Vec3 w = ambient(p, t);
  if (settings_.mode != WindMode::Sph || !air_)
    for (const WindEmitter& e : settings_.emitters) w += jet(e, p);
  return w;
}

// The lattice table: at most this many values per noise; a larger span samples per point.
constexpr int64_t kMaxTableValues = 1 << 16;
// Lattice indices beyond this are left to ambient() (whose int64 conversion they still fit).
constexpr float kMaxLatticeIndex = 1e9f;

void GustSampler::prepare(const WindField& field, const Vec3* points, size_t count) {
  field_ = field;
  field_.setAirFlow(nullptr);
  const WindSettings& s = field_.settings_;
  position_.assign(points, points + count);
  flight_.resize(count);
  for (int n = 0; n < 2; ++n) {
    row_[n].resize(count);
    b_[n].resize(count);
  }
  // Without gusts ambient() is the prevailing wind; a non-finite point or an across span beyond
  // the table samples per point.
  tableable_ = s.mode == WindMode::Gusty && field_.speed_ > 0.0f && count > 0;
  if (!tableable_) return;
  // Per point, the steps of ambient() that do not depend on t.
  flightMin_ = std::numeric_limits<float>::infinity();
  flightMax_ = -flightMin_;
  int32_t rowMin[2] = {INT32_MAX, INT32_MAX}, rowMax[2] = {INT32_MIN, INT32_MIN};
  for (size_t k = 0; k < count; ++k) {
    const Vec3& p = position_[k];
    const float flight = p.dot(field_.dir_) / field_.speed_;
    const float acrossDist = field_.acrossIsX_ ? p.x() : p.dot(field_.across_);
    const float sigma = acrossDist / s.gustScale;
    const float v[2] = {sigma, sigma + 57.1f};
    for (int n = 0; n < 2; ++n) {
      const float fv = std::floor(v[n]);
      if (!(std::fabs(fv) < kMaxLatticeIndex)) {
        tableable_ = false;
        return;
      }
      row_[n][k] = int32_t(fv);
      b_[n][k] = WindField::quintic(v[n] - fv);
      rowMin[n] = std::min(rowMin[n], row_[n][k]);
      rowMax[n] = std::max(rowMax[n], row_[n][k]);
    }
    if (!std::isfinite(flight)) {
      tableable_ = false;
      return;
    }
    flight_[k] = flight;
    flightMin_ = std::min(flightMin_, flight);
    flightMax_ = std::max(flightMax_, flight);
  }
  for (int n = 0; n < 2; ++n) {
    const int64_t rows = int64_t(rowMax[n]) - rowMin[n] + 2;  // each point reads its row and the next
    if (rows > kMaxTableValues / 2) {
      tableable_ = false;
      return;
    }
    table_[n].firstRow = rowMin[n];
    table_[n].rows = int32_t(rows);
    for (int32_t& r : row_[n]) r -= rowMin[n];
  }
}

bool GustSampler::preparedFor(const WindField& field, size_t count) const {
  const WindSettings& a = field.settings_;
  const WindSettings& b = field_.settings_;
  if (position_.size() != count || a.mode != b.mode || a.velocity != b.velocity) return false;
  return a.mode != WindMode::Gusty || (a.gustStrength == b.gustStrength && a.gustPeriod == b.gustPeriod &&
                                       a.gustScale == b.gustScale && a.gustTurn == b.gustTurn && a.seed == b.seed);
}

void GustSampler::beginFrame(float t) {
  t_ = t;
  tabled_ = false;
  if (!tableable_) return;
  const WindSettings& s = field_.settings_;
  // τ = (t − flight) / period falls as the flight grows (each rounding is monotone), so the
  // points' lattice columns lie between those of the longest and the shortest flight.
  const float tauLow = (t - flightMax_) / s.gustPeriod, tauHigh = (t - flightMin_) / s.gustPeriod;
  const float low[2] = {std::floor(tauLow), std::floor(tauLow + 101.3f)};
  const float high[2] = {std::floor(tauHigh), std::floor(tauHigh + 101.3f)};
  const uint64_t seeds[2] = {s.seed, s.seed ^ kTurnSeed};
  for (int n = 0; n < 2; ++n) {
    if (!(std::fabs(low[n]) < kMaxLatticeIndex && std::fabs(high[n]) < kMaxLatticeIndex)) return;
    const int64_t columns = int64_t(high[n]) - int64_t(low[n]) + 2;
    if (columns * table_[n].rows > kMaxTableValues) return;
  }
  for (int n = 0; n < 2; ++n) {
    Table& T = table_[n];
    T.firstColumn = int64_t(low[n]);
    const int64_t columns = int64_t(high[n]) - T.firstColumn + 2;
    T.values.resize(size_t(columns * T.rows));
    for (int64_t c = 0; c < columns; ++c)
      for (int32_t r = 0; r < T.rows; ++r)
        T.values[size_t(c * T.rows + r)] = lattice(T.firstColumn + c, int64_t(T.firstRow) + r, seeds[n]);
  }
  tabled_ = true;
}

namespace {

// Four lanes: each lane does the scalar steps of ambient(), operation for operation, so gives
// the same bits.
using F4 = float __attribute__((vector_size(16)));
using I4 = int32_t __attribute__((vector_size(16)));

inline F4 load4(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline I4 load4(const int32_t* p) {
  I4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// std::floor for |x| < 2³¹: truncate, step down where that rounded up, keep the sign of zero.
inline F4 floor4(F4 x) {
  F4 f = __builtin_convertvector(__builtin_convertvector(x, I4), F4);
  f = f > x ? f - 1.0f : f;
  return F4(I4(f) | (I4(x) & I4(F4{-0.0f, -0.0f, -0.0f, -0.0f})));
}
inline F4 quintic4(F4 x) { return x * x * x * (x * (x * 6.0f - 15.0f) + 10.0f); }

}  // namespace

void GustSampler::ambient4(size_t k, float* x, float* y, float* z) const {
  if (!tabled_) {
    for (int l = 0; l < 4; ++l) {
      const Vec3 w = ambient(k + size_t(l));
      x[l] = w.x(), y[l] = w.y(), z[l] = w.z();
    }
    return;
  }
  const WindSettings& s = field_.settings_;
  const F4 tau = (t_ - load4(flight_.data() + k)) / s.gustPeriod;
  F4 noise[2];
  for (int n = 0; n < 2; ++n) {
    const Table& T = table_[n];
    const F4 u = n == 0 ? tau : tau + 101.3f;
    const F4 fu = floor4(u);
    const F4 a = quintic4(u - fu);
    // The table's columns are a few of the frame's: the offsets fit 32 bits.
    const I4 at = (__builtin_convertvector(fu, I4) - int32_t(T.firstColumn)) * T.rows + load4(row_[n].data() + k);
    F4 L00, L10, L01, L11;
    for (int l = 0; l < 4; ++l) {
      const float* L = T.values.data() + at[l];
      L00[l] = L[0], L10[l] = L[T.rows], L01[l] = L[1], L11[l] = L[T.rows + 1];
    }
    const F4 x0 = L00 + a * (L10 - L00);
    const F4 x1 = L01 + a * (L11 - L01);
    noise[n] = x0 + load4(b_[n].data() + k) * (x1 - x0);
  }
  // WindField::gustWind, with sinCos's series where every lane's angle is below 0.5.
  const F4 angle = s.gustTurn * noise[1];
  F4 sn, c;
  const F4 small = F4(I4(angle) & 0x7fffffff) < 0.5f;
  if ((small[0] != 0) & (small[1] != 0) & (small[2] != 0) & (small[3] != 0)) {
    const F4 x2 = angle * angle;
    sn = angle * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f))));
    c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f))));
  } else {
    for (int l = 0; l < 4; ++l) {
      float sl, cl;
      sinCos(angle[l], &sl, &cl);
      sn[l] = sl;
      c[l] = cl;
    }
  }
  const Vec3& dir = field_.dir_;
  const F4 grown = 1.0f + s.gustStrength * noise[0];
  const F4 scale = field_.speed_ * (grown > 0.0f ? grown : F4{});
  const F4 wx = scale * (dir.x() * c + dir.z() * sn), wy = scale * dir.y(), wz = scale * (dir.z() * c - dir.x() * sn);
  std::memcpy(x, &wx, sizeof wx);
  std::memcpy(y, &wy, sizeof wy);
  std::memcpy(z, &wz, sizeof wz);
}

}  // namespace tendril::env

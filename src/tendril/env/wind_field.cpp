#include "tendril/env/wind_field.h"

#include "tendril/core/random.h"

#include <cmath>
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
  points_.resize(count);
  for (size_t k = 0; k < count; ++k) points_[k].position = points[k];
  // Without gusts ambient() is the prevailing wind; a non-finite point or an across span beyond
  // the table samples per point.
  tableable_ = s.mode == WindMode::Gusty && field_.speed_ > 0.0f && count > 0;
  if (!tableable_) return;
  // Per point, the steps of ambient() that do not depend on t.
  flightMin_ = std::numeric_limits<float>::infinity();
  flightMax_ = -flightMin_;
  int32_t rowMin[2] = {INT32_MAX, INT32_MAX}, rowMax[2] = {INT32_MIN, INT32_MIN};
  for (Point& q : points_) {
    const Vec3& p = q.position;
    q.flight = p.dot(field_.dir_) / field_.speed_;
    const float acrossDist = field_.acrossIsX_ ? p.x() : p.dot(field_.across_);
    const float sigma = acrossDist / s.gustScale;
    const float v[2] = {sigma, sigma + 57.1f};
    for (int n = 0; n < 2; ++n) {
      const float fv = std::floor(v[n]);
      if (!(std::fabs(fv) < kMaxLatticeIndex)) {
        tableable_ = false;
        return;
      }
      q.row[n] = int32_t(fv);
      q.b[n] = WindField::quintic(v[n] - fv);
      rowMin[n] = std::min(rowMin[n], q.row[n]);
      rowMax[n] = std::max(rowMax[n], q.row[n]);
    }
    if (!std::isfinite(q.flight)) {
      tableable_ = false;
      return;
    }
    flightMin_ = std::min(flightMin_, q.flight);
    flightMax_ = std::max(flightMax_, q.flight);
  }
  for (int n = 0; n < 2; ++n) {
    const int64_t rows = int64_t(rowMax[n]) - rowMin[n] + 2;  // each point reads its row and the next
    if (rows > kMaxTableValues / 2) {
      tableable_ = false;
      return;
    }
    table_[n].firstRow = rowMin[n];
    table_[n].rows = int32_t(rows);
  }
  for (Point& q : points_)
    for (int n = 0; n < 2; ++n) q.row[n] -= table_[n].firstRow;
}

bool GustSampler::preparedFor(const WindField& field, size_t count) const {
  const WindSettings& a = field.settings_;
  const WindSettings& b = field_.settings_;
  if (points_.size() != count || a.mode != b.mode || a.velocity != b.velocity) return false;
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

}  // namespace tendril::env

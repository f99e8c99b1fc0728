#include "tendril/env/wind_field.h"

#include "tendril/core/random.h"

#include <cmath>

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

void WindField::prepare() {
  speed_ = settings_.velocity.norm();
  dir_ = speed_ > 0.0f ? Vec3(settings_.velocity / speed_) : Vec3::UnitX();
  const Vec3 across = dir_.cross(Vec3::UnitY());
  acrossIsX_ = !(across.squaredNorm() > 1e-8f);
  across_ = acrossIsX_ ? Vec3::UnitX() : across.normalized();
}

static float quintic(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

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
  const Vec3& dir = dir_;
  // Gust fronts travel downwind with the wind: the noise sees the time a parcel of air left a
  // plane through the origin, and the position across the wind.
  float acrossDist = acrossIsX_ ? p.x() : p.dot(across_);
  float tau = (t - p.dot(dir) / speed) / s.gustPeriod;
  float sigma = acrossDist / s.gustScale;
  float gust = noise(tau, sigma, s.seed);
  float turn = noise(tau + 101.3f, sigma + 57.1f, s.seed ^ 0x5bd1e995ull);
  // dir turned by θ about +Y: (x cos θ + z sin θ, y, z cos θ − x sin θ); θ is at most
  // gustTurn, mostly a few degrees (sinCos's short series).
  float c, sn;
  sinCos(s.gustTurn * turn, &sn, &c);
  const Vec3 turned(dir.x() * c + dir.z() * sn, dir.y(), dir.z() * c - dir.x() * sn);
  return speed * std::max(0.0f, 1.0f + s.gustStrength * gust) * turned;
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

}  // namespace tendril::env

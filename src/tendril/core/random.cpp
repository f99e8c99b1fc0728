#include "tendril/core/random.h"

#include <cmath>

namespace tendril {

Rng::Rng(const RandomKey& k) {
  // Each field passes through the mixer before the next is folded in, so keys that differ in
  // any one field give unrelated streams.
  uint64_t h = mix64(k.seed ^ 0x6a09e667f3bcc908ull);
  h = mix64(h ^ (k.plant + 0x3c6ef372fe94f82bull));
  h = mix64(h ^ (k.node + 0xa54ff53a5f1d36f1ull));
  h = mix64(h ^ (k.step + 0x510e527fade682d1ull));
  h = mix64(h ^ (k.purpose + 0x9b05688c2b3e6c1full));
  key_ = h;
}

float Rng::normal() {
  float u1 = uniform();
  float u2 = uniform();
  float r = std::sqrt(-2.0f * std::log(1.0f - u1));  // 1-u1 in (0, 1]
  return r * std::cos(kTwoPi * u2);
}

Vec3 Rng::unitVector() {
  float z = uniform(-1.0f, 1.0f);
  float phi = kTwoPi * uniform();
  float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return Vec3(r * std::cos(phi), z, r * std::sin(phi));
}

Vec3 Rng::inCone(const Vec3& axis, float halfAngle) {
  float cosMax = std::cos(halfAngle);
  float c = 1.0f - uniform() * (1.0f - cosMax);
  float s = std::sqrt(std::max(0.0f, 1.0f - c * c));
  float phi = kTwoPi * uniform();
  Vec3 u = anyPerpendicular(axis);
  Vec3 v = axis.cross(u);
  return (axis * c + (u * std::cos(phi) + v * std::sin(phi)) * s).normalized();
}

}  // namespace tendril

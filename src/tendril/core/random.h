// Counter-based random numbers. A stream is keyed by *where* it is used — (scene seed,
// plant id, node id, step, purpose) — never by shared sequential state, so results do not
// depend on which thread ran first (the pbrt-v4 idea; see docs/architecture.md).
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <string_view>

namespace tendril {

// Stable 64-bit id for a purpose string, e.g. purposeId("climb.branch"). constexpr FNV-1a,
// so the same name always gives the same stream on every build.
constexpr uint64_t purposeId(std::string_view name) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (char c : name) {
    h ^= static_cast<uint8_t>(c);
    h *= 0x100000001b3ull;
  }
  return h;
}

// SplitMix64's finaliser: a bijective 64-bit mixer with full avalanche.
constexpr uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

struct RandomKey {
  uint64_t seed = 0;     // scene seed (or a plant's own seed)
  uint64_t plant = 0;    // plant id
  uint64_t node = 0;     // node / tip / particle id
  uint64_t step = 0;     // simulation or growth step
  uint64_t purpose = 0;  // purposeId("module.what")
};

// A counter-based stream: value i of the stream is mix64(key + (i+1)·golden). Cheap to create,
// so make one where it is needed instead of passing generators around.
class Rng {
 public:
  explicit Rng(const RandomKey& k);
  explicit Rng(uint64_t key) : key_(key) {}

  uint64_t nextU64() { return mix64(key_ + (++counter_) * 0x9e3779b97f4a7c15ull); }
  uint32_t nextU32() { return static_cast<uint32_t>(nextU64() >> 32); }
  // Uniform in [0, 1): the top 24 bits, exactly representable as float.
  float uniform() { return static_cast<float>(nextU64() >> 40) * (1.0f / 16777216.0f); }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  bool bernoulli(float p) { return uniform() < p; }
  // Uniform integer in [0, n).
  uint32_t below(uint32_t n) { return static_cast<uint32_t>((nextU64() >> 32) * n >> 32); }
  // Standard normal (Box-Muller; uses two draws).
  float normal();
  // Uniform direction on the unit sphere.
  Vec3 unitVector();
  // Uniform direction within a cone of half-angle `halfAngle` around unit `axis`.
  Vec3 inCone(const Vec3& axis, float halfAngle);

  uint64_t key() const { return key_; }

 private:
  uint64_t key_;
  uint64_t counter_ = 0;
};

}  // namespace tendril

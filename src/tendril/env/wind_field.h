// The wind w(x, t) every growth and motion model samples (DESIGN.md: the Environment answers
// "wind velocity at (x, t)").
//
// Three modes:
//  * constant — the prevailing velocity everywhere, plus the emitters' jets;
//  * gusty    — the prevailing wind modulated by smooth value noise: gust fronts travel with the
//               wind (the noise is a function of t − (x·ŵ)/|w| and of the position across the
//               wind), the speed varies by ±gustStrength and the direction wanders by ±gustTurn
//               about +Y; plus the emitters' jets;
//  * sph      — the velocity of simulated air (seed 000 §5.3) from an AirFlow the owner of the
//               simulation installs (wind/sph.h); where there is no air it falls back to the
//               constant mode.
// An emitter (seed 000 §5.3: position, direction, speed, rate, area) blows a round jet of the
// given radius that widens by `spread` and slows as its area grows (momentum flux conserved)
// until `reach`; its rate is the number of air particles per second it spawns in sph mode.
//
// The noise is counter-based (keyed by the wind's seed), so w(x, t) is a pure function: the
// same scene gives the same wind on any thread.
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <vector>

namespace tendril::env {

struct WindEmitter {
  Vec3 position = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();  // unit
  float speed = 5.0f;              // m/s at the nozzle
  float radius = 0.5f;             // m (the paper's area is π radius²)
  float reach = 10.0f;             // m along the direction
  float spread = radians(8.0f);    // half-angle the jet widens by
  float rate = 0.0f;               // air particles per second in sph mode (0 = from speed and area)
};

enum class WindMode { Constant, Gusty, Sph };

struct WindSettings {
  WindMode mode = WindMode::Constant;
  Vec3 velocity = Vec3::Zero();  // prevailing wind (m/s)
  float gustStrength = 0.4f;     // gusty: speed varies by ± this fraction of the prevailing speed
  float gustPeriod = 3.0f;       // s between independent gusts
  float gustScale = 6.0f;        // m across the wind between independent gusts
  float gustTurn = radians(12.0f);  // direction wander about +Y
  uint64_t seed = 0;
  std::vector<WindEmitter> emitters;

  bool calm() const;  // no wind anywhere, ever
};

// Simulated air the sph mode samples.
class AirFlow {
 public:
  virtual ~AirFlow() = default;
  // Air velocity at p; `covered` false where no air particle is near.
  virtual Vec3 velocityAt(const Vec3& p, bool* covered) const = 0;
};

class WindField {
 public:
  WindField() = default;
  explicit WindField(WindSettings settings) : settings_(std::move(settings)) { prepare(); }

  const WindSettings& settings() const { return settings_; }
  void setSettings(WindSettings settings) {
    settings_ = std::move(settings);
    prepare();
  }
  // The simulated air for sph mode (not owned; null = none).
  void setAirFlow(const AirFlow* air) { air_ = air; }

  Vec3 sample(const Vec3& p, float t) const;
  // The prevailing wind modulated by gusts, without the emitters' jets.
  Vec3 ambient(const Vec3& p, float t) const;
  // One emitter's jet at p.
  static Vec3 jet(const WindEmitter& e, const Vec3& p);
  // Smooth value noise in [−1, 1] over the plane (continuous, C2), keyed by seed.
  static float noise(float u, float v, uint64_t seed);

 private:
  void prepare();  // the frame below, from settings_

  WindSettings settings_;
  const AirFlow* air_ = nullptr;
  // The prevailing wind's speed, direction and the horizontal direction across it (gusty).
  float speed_ = 0.0f;
  Vec3 dir_ = Vec3::UnitX(), across_ = Vec3::UnitX();
  bool acrossIsX_ = true;  // a vertical wind: its "across" position is x
};

}  // namespace tendril::env

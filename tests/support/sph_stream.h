// Air streaming through a box, for tests of the air and of its coupling with plants.
#pragma once

#include "tendril/env/environment.h"
#include "tendril/wind/sph.h"

namespace tendril::test {

// The box of `settings` filled with air moving at `speed` along +x, kept streaming by a round
// emitter of `radius` just inside the box's upstream face at height 0.4 m.
inline wind::SphAir streamingAir(const wind::SphSettings& settings, const env::Environment& env, float speed,
                                 float radius) {
  wind::SphAir air(settings);
  air.fillBox(settings.domainMin, settings.domainMax, env, Vec3(speed, 0, 0));
  wind::SphEmitter e;
  e.position = Vec3(settings.domainMin.x() + 0.02f, 0.4f, 0.0f);
  e.direction = Vec3(1, 0, 0);
  e.speed = speed;
  e.radius = radius;
  air.addEmitter(e);
  return air;
}

// Mean downwind air speed (m/s) over 5 × 5 × 5 points spread evenly over the box [lo, hi].
inline float meanSpeedX(const wind::SphAir& air, const Vec3& lo, const Vec3& hi) {
  double sum = 0.0;
  int n = 0;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j)
      for (int k = 0; k <= 4; ++k) {
        sum += air.velocityAt(lo + (hi - lo).cwiseProduct(Vec3(float(i), float(j), float(k)) / 4.0f)).x();
        ++n;
      }
  return float(sum / n);
}

}  // namespace tendril::test

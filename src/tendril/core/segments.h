// Closest points of two line segments (particle collisions, stem tests).
#pragma once

#include "tendril/core/math.h"

#include <algorithm>

namespace tendril {

// The closest points c1 on p1-q1 and c2 on p2-q2 (the squared distance minimised over both
// parameters, clamped to the segments; degenerate segments are points). Inline: particle
// collisions call it for every capsule pair.
inline void closestSegmentPoints(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3* c1, Vec3* c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const float a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  float s = 0.0f, t = 0.0f;
  if (a <= 1e-12f && e <= 1e-12f) {
    *c1 = p1;
    *c2 = p2;
    return;
  }
  if (a <= 1e-12f) {
    t = std::clamp(f / e, 0.0f, 1.0f);
  } else {
    const float c = d1.dot(r);
    if (e <= 1e-12f) {
      s = std::clamp(-c / a, 0.0f, 1.0f);
    } else {
      const float b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-12f ? std::clamp((b * f - c * e) / denom, 0.0f, 1.0f) : 0.0f;
      t = (b * s + f) / e;
      if (t < 0.0f) {
        t = 0.0f;
        s = std::clamp(-c / a, 0.0f, 1.0f);
      } else if (t > 1.0f) {
        t = 1.0f;
        s = std::clamp((b - c) / a, 0.0f, 1.0f);
      }
    }
  }
  *c1 = p1 + d1 * s;
  *c2 = p2 + d2 * t;
}

}  // namespace tendril

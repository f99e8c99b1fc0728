// Where a plant may start: one rule for the seeds of every growth model (climbing, particle,
// L-system and graph plants), so that the same seed point is accepted or refused alike.
#pragma once

#include "tendril/env/environment.h"

#include <string>

namespace tendril::env {

// How far along its direction a seed on a surface must grow free of obstacles (m).
inline constexpr float kSeedProbeDistance = 0.005f;

// True when a plant seeded at `position`, growing along `direction`, would start inside an
// obstacle: the point itself is inside a closed obstacle, or it lies on a surface (closer to
// one than kSeedProbeDistance) and the first kSeedProbeDistance of its growth enter a closed
// obstacle — e.g. a seed on the ground at the foot of a wall that stands on it, growing up into
// the wall. A seed exactly on a surface, growing away from it or along it, is outside.
// The growth start is tested against each obstacle on its own: where two surfaces meet (the
// ground and the wall's foot) the nearest surface point is a tie between them and says
// nothing about the other.
bool seedInsideObstacle(const Environment& env, const Vec3& position, const Vec3& direction);

// Throws Error(source, "", "seed position (x, y, z) lies inside an obstacle") when
// seedInsideObstacle; the Session places it at the plant's "position".
void checkSeedPosition(const Environment& env, const Vec3& position, const Vec3& direction,
                       const std::string& source = "");

}  // namespace tendril::env

// A plant that stops growing in its first steps, or stays far below its species' size, and why:
// one rule for every growth model that has a GrowthGauge (models/capabilities.h). The Session
// reports what it finds as warnings, `tendril validate` grows each plant alone for its first
// steps and reports seeds that will not grow, and the studio shows it in its status bar.
#pragma once

#include "tendril/env/environment.h"
#include "tendril/models/plant_spec.h"
#include "tendril/models/registry.h"

#include <cstdint>
#include <optional>
#include <string>

namespace tendril::models {

enum class GrowthCause : uint8_t {
  SeedBlocked,  // the seed's growth direction meets an obstacle close by (a seed under a car)
  Blocked,      // obstacles (or repelling strokes) leave its shoots no room to grow
  NoSupport,    // a climber with nothing to climb within reach
  NoLight,      // too little light for its growth rate
  Crowded,      // other stems already fill the space its shoots grow into
  Cap,          // it reached a cap (max segments, max particles)
  Shortened,    // its internodes fell below the species' minimum length
  Rule,         // its species' die rule
  Unknown,      // none of the causes above applies
};
const char* causeName(GrowthCause cause);  // "seed-blocked", "no-support", …

// A plant stops early when it has stopped growing (and not because its settings end it there)
// with under this fraction of what its species grows unhindered in as many steps, and at least
// in kFirstSteps; where its model cannot say what that is, when it stopped in its first
// kFirstSteps steps …
inline constexpr double kStoppedFraction = 0.5;
inline constexpr uint32_t kFirstSteps = 30;
// … and is small when, still growing after kSmallAfterSteps steps, it has under this fraction.
inline constexpr double kSmallFraction = 0.25;
inline constexpr uint32_t kSmallAfterSteps = 200;
// How far along its growth direction an obstacle counts as over the seed (m).
inline constexpr float kSeedClearance = 0.5f;

struct GrowthProblem {
  GrowthCause cause = GrowthCause::Unknown;
  bool stopped = false;  // it has stopped growing (else it still grows, far below its size)
  std::string message;   // one line naming the plant, what it grew and the cause
  std::string why;       // the cause alone, e.g. "no support in reach: …" (the end of the message)
};

// What is wrong with plant `index` of `system` (the Session's plant `spec`), or nothing for a
// plant that grows as its species does or whose model has no GrowthGauge. Reads the plant's
// snapshot and asks `env` only for a plant that is found wanting.
std::optional<GrowthProblem> diagnoseGrowth(const PlantSystem& system, size_t index, const PlantSpec& spec,
                                            const env::Environment& env);

}  // namespace tendril::models

#include "tendril/models/diagnosis.h"

#include "tendril/env/seed_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace tendril::models {

const char* causeName(GrowthCause cause) {
  switch (cause) {
    case GrowthCause::SeedBlocked: return "seed-blocked";
    case GrowthCause::Blocked: return "blocked";
    case GrowthCause::NoSupport: return "no-support";
    case GrowthCause::NoLight: return "no-light";
    case GrowthCause::Crowded: return "crowded";
    case GrowthCause::Cap: return "cap";
    case GrowthCause::Shortened: return "shortened";
    case GrowthCause::Rule: return "rule";
    case GrowthCause::Unknown: return "unknown";
  }
  return "unknown";
}

namespace {

// Below this mean exposure at its shoot tips a plant whose growth follows the light is starved.
constexpr float kDarkExposure = 0.25f;
// A climber has no support when no surface that does not face its growth direction (the
// ground it grows up from does) lies within reach: surfaces with n·d above this are skipped.
constexpr float kSupportFacing = 0.5f;

std::string amount(double value, const char* unit) {
  if (std::strcmp(unit, "m of stem") == 0) return fmt::format("{:.2f} {}", value, unit);
  return fmt::format("{:.0f} {}", value, unit);
}

// The end recorded on the plant's dead tips that says most about it: the main stem's (the
// first axis, order 0), else the most common one; Unknown when none is recorded.
plant::TipEnd recordedEnd(const plant::PlantModel& m, plant::TipEnd seedEnd) {
  if (m.nodeCount() == 0) return seedEnd;
  std::array<size_t, 16> counts{};
  plant::TipEnd main = plant::TipEnd::Unknown;
  for (size_t i = 0; i < m.nodeCount(); ++i) {
    const uint32_t f = m.flags[i];
    if (!(f & plant::kNodeDead) || (f & plant::kNodeBroken)) continue;
    const plant::TipEnd e = plant::tipEnd(f);
    if (e == plant::TipEnd::Unknown) continue;
    ++counts[size_t(e)];
    if (m.order[i] == 0 && main == plant::TipEnd::Unknown) main = e;
  }
  if (main != plant::TipEnd::Unknown) return main;
  size_t best = 0;
  for (size_t e = 1; e < counts.size(); ++e)
    if (counts[e] > counts[best]) best = e;
  return counts[best] > 0 ? plant::TipEnd(best) : plant::TipEnd::Unknown;
}

// True when a surface the shoot is not growing away from lies within `reach` of the straight
// path of its first `run` metres from the seed (sampled every half reach, from half a reach
// out: at the seed itself the surface it stands on has no side to face).
bool supportAlong(const env::Environment& env, const Vec3& seed, const Vec3& dir, float reach, float run) {
  const float stride = 0.5f * reach;
  for (float t = stride; t <= std::max(run, stride) + 1e-6f; t += stride)
    if (auto sp = env.closestPointFacing(seed + t * dir, reach, dir, kSupportFacing); sp && sp->away.dot(dir) <= kSupportFacing)
      return true;
  return false;
}

// Mean light exposure at the plant's growing tips (at the seed when none grows).
float tipExposure(const plant::PlantModel& m, const PlantSpec& spec, const env::Environment& env) {
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < m.nodeCount(); ++i)
    if (m.flags[i] & plant::kNodeApex) {
      sum += env.light(m.tip(i)).exposure;
      ++n;
    }
  if (n == 0) return env.light(spec.position).exposure;
  return float(sum / double(n));
}

}  // namespace

std::optional<GrowthProblem> diagnoseGrowth(const PlantSystem& system, size_t index, const PlantSpec& spec,
                                            const env::Environment& env) {
  const GrowthGauge* gauge = system.growthGauge();
  if (!gauge) return std::nullopt;
  const GrowthGauge::Reading r = gauge->growthReading(index);
  // Stopped: measured against what its species grows in as many steps, and at least in its
  // first kFirstSteps (a plant that stops in its first steps is judged by those); where the
  // model cannot say what that is, by whether it stopped within its first kFirstSteps.
  // Small: still growing, but far below its species' size for its steps so far.
  double expected = 0.0;
  bool stopped = false, small = false;
  if (!r.growing && !r.complete) {
    expected = gauge->unhinderedGrowth(index, std::max(r.steps, kFirstSteps));
    stopped = expected > 0.0 ? r.grown < kStoppedFraction * expected : r.lastGrowth < kFirstSteps;
  } else if (r.growing && r.steps >= kSmallAfterSteps) {
    expected = gauge->unhinderedGrowth(index, r.steps);
    small = expected > 0.0 && r.grown < kSmallFraction * expected;
  }
  if (!stopped && !small) return std::nullopt;

  const plant::PlantModel m = system.snapshot(index);
  const Vec3 dir = spec.direction.normalized();
  const std::optional<env::RayHit> ahead = env.rayCast(spec.position, dir, kSeedClearance, env::kSeedProbeDistance);
  GrowthProblem p;
  p.stopped = stopped;
  std::string why;
  auto seedBlocked = [&] {
    p.cause = GrowthCause::SeedBlocked;
    why = fmt::format("seed under an obstacle: its growth direction meets a surface {:.2f} m from the seed; move "
                      "the seed or turn its direction",
                      ahead->t);
  };
  auto noLight = [&](float exposure) {
    p.cause = GrowthCause::NoLight;
    why = fmt::format("too little light: {:.0f} % exposure at its shoot tips; move it or the lights", 100.0f * exposure);
  };

  const plant::TipEnd recorded = recordedEnd(m, r.seedEnd);
  const float exposure = r.lightDriven ? tipExposure(m, spec, env) : 1.0f;
  if (!r.cap.empty()) {
    p.cause = GrowthCause::Cap;
    why = fmt::format("it reached {}; raise it to grow further", r.cap);
  } else if (small && exposure < kDarkExposure) {
    if (ahead) {  // under a car: in its shade
      seedBlocked();
      why += fmt::format(" (in its shade the shoot tips get {:.0f} % light)", 100.0f * exposure);
    } else {
      noLight(exposure);
    }
  } else if (recorded == plant::TipEnd::Blocked || (recorded == plant::TipEnd::Unknown && ahead)) {
    if (ahead) {
      seedBlocked();
    } else {
      p.cause = GrowthCause::Blocked;
      why = "obstacles (or strokes painted to repel growth) leave its shoots no room to grow";
    }
  } else if (recorded == plant::TipEnd::NoSupport) {
    p.cause = GrowthCause::NoSupport;
    why = fmt::format("no support in reach: its shoots found nothing to climb within {:.2f} m in their first {:.2f} m; "
                      "seed it nearer a wall or a trunk",
                      r.supportReach, r.unsupportedRun);
  } else if (recorded == plant::TipEnd::Crowded) {
    p.cause = GrowthCause::Crowded;
    why = "crowding: stems (its own or other plants') already fill the space its shoots grow into";
  } else if (recorded == plant::TipEnd::Capped) {
    p.cause = GrowthCause::Cap;
    why = "it reached its species' cap on segments or particles; raise it to grow further";
  } else if (recorded == plant::TipEnd::Shortened) {
    p.cause = GrowthCause::Shortened;
    why = "its internodes became shorter than the species' min_length (its decrease rule, or the wind)";
  } else if (recorded == plant::TipEnd::Rule) {
    p.cause = GrowthCause::Rule;
    why = "its species' die rule ended its shoots";
  } else if (r.supportReach > 0.0f && !supportAlong(env, spec.position, dir, r.supportReach, r.unsupportedRun)) {
    p.cause = GrowthCause::NoSupport;
    why = fmt::format("no support in reach: nothing to climb within {:.2f} m of its first {:.2f} m of growth; seed it "
                      "nearer a wall or a trunk",
                      r.supportReach, r.unsupportedRun);
  } else if (exposure < kDarkExposure) {
    noLight(exposure);
  } else {
    p.cause = GrowthCause::Unknown;
    why = "none of the causes Tendril checks (an obstacle over the seed, support in reach, light, crowding, caps) "
          "applies: its own settings stopped it";
  }

  p.why = why;
  const std::string grown = amount(r.grown, r.unit);
  if (stopped && expected > 0.0)
    p.message = fmt::format("plant \"{}\" stopped growing with {} where its species grows {} unhindered in {} steps: {}",
                            spec.name, grown, amount(expected, r.unit), std::max(r.steps, kFirstSteps), why);
  else if (stopped)
    p.message = fmt::format("plant \"{}\" stopped growing in its first steps (step {}, {}): {}", spec.name,
                            r.lastGrowth, grown, why);
  else
    p.message = fmt::format("plant \"{}\" has grown {} in {} steps, under a quarter of the {} its species grows "
                            "unhindered: {}",
                            spec.name, grown, r.steps, amount(expected, r.unit), why);
  return p;
}

}  // namespace tendril::models

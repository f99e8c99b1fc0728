// Saving and restoring the simulated air exactly (sessions, undo).
#include "tendril/wind/sph.h"

#include <fmt/format.h>

namespace tendril::wind {

namespace {

constexpr uint32_t kSphTag = 0x48505331;  // "1SPH"

}  // namespace

// The neighbour grid and the plant coupling records are rebuilt by every step from these; the
// wall tables come from the settings.
void SphAir::saveState(ArchiveWriter& out) const {
  out.tag(kSphTag);
  out.vector(emitters_);
  out.vector(emitterClock_);
  out.f32(mass_), out.f32(h_), out.f32(time_);
  out.u64(steps_);
  out.boolean(warnedCapacity_), out.boolean(warnedSubsteps_);
  out.vector(x_), out.vector(v_), out.vector(rho_);
  out.vector(sdfBudget_), out.vector(sdf_), out.vector(sdfNormal_), out.vector(dead_);
}

void SphAir::loadState(ArchiveReader& in) {
  in.tag(kSphTag, "the simulated air");
  in.vector(emitters_);
  in.vector(emitterClock_);
  if (emitterClock_.size() != emitters_.size()) in.fail("the saved air's emitter records differ in length");
  mass_ = in.f32(), h_ = in.f32(), time_ = in.f32();
  steps_ = in.u64();
  warnedCapacity_ = in.boolean(), warnedSubsteps_ = in.boolean();
  in.vector(x_), in.vector(v_), in.vector(rho_);
  in.vector(sdfBudget_), in.vector(sdf_), in.vector(sdfNormal_), in.vector(dead_);
  const size_t n = x_.size();
  if (v_.size() != n || rho_.size() != n || sdfBudget_.size() != n || sdf_.size() != n || sdfNormal_.size() != n ||
      dead_.size() != n)
    in.fail("the saved air's particle arrays differ in length");
  if (n > settings_.maxParticles)
    in.fail(fmt::format("the saved air has {} particles, more than its limit {}", n, settings_.maxParticles));
  buildGrid();  // velocityAt samples the restored air, not the grid of the air before
}

}  // namespace tendril::wind

// Saving and restoring the simulated air exactly (sessions, undo).
#include "tendril/wind/sph.h"

#include <fmt/format.h>

#include <cmath>

namespace tendril::wind {

namespace {

constexpr uint32_t kSphTag = 0x48505332;        // "2SPH": with the position-based solver's pressures
constexpr uint32_t kSphTagBefore = 0x48505331;  // "1SPH": without them (read as 0)

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
  out.vector(p_);
}

void SphAir::loadState(ArchiveReader& in) {
  const size_t tagAt = in.position();
  const uint32_t tag = in.u32();
  if (tag != kSphTag && tag != kSphTagBefore) in.fail(tagAt, "expected the start of the simulated air (the data is damaged)");
  in.vector(emitters_);
  in.vector(emitterClock_);
  if (emitterClock_.size() != emitters_.size()) in.fail("the saved air's emitter records differ in length");
  for (const SphEmitter& e : emitters_) {
    try {
      checkEmitter(e);
    } catch (const Error& error) {
      in.fail(fmt::format("a saved emitter is invalid: {}", error.what()));
    }
    if (!(std::abs(e.direction.squaredNorm() - 1.0f) < 1e-4f))
      in.fail("a saved emitter's direction is not a unit vector");
  }
  for (const double clock : emitterClock_)
    if (!(clock >= 0.0 && clock < 1e6)) in.fail("a saved emitter's clock is out of range");
  // The mass and support follow from the settings; the saved ones (bit-exact for an exact
  // continuation) must be those, up to another machine's round-off.
  const float mass = in.f32(), h = in.f32();
  if (!(std::abs(mass - mass_) <= 1e-4f * mass_ && std::abs(h - h_) <= 1e-4f * h_))
    in.fail(fmt::format("the saved air's particle mass {} kg and support {} m are not its settings' ({} kg, {} m)", mass,
                        h, mass_, h_));
  mass_ = mass, h_ = h, time_ = in.f32();
  sdfRevision_ = 0;  // the distances are queried again at the next step
  steps_ = in.u64();
  warnedCapacity_ = in.boolean(), warnedSubsteps_ = in.boolean();
  in.vector(x_), in.vector(v_), in.vector(rho_);
  in.vector(sdfBudget_), in.vector(sdf_), in.vector(sdfNormal_), in.vector(dead_);
  const size_t n = x_.size();
  if (tag == kSphTag)
    in.vector(p_);
  else
    p_.assign(n, 0.0f);
  if (v_.size() != n || rho_.size() != n || p_.size() != n || sdfBudget_.size() != n || sdf_.size() != n ||
      sdfNormal_.size() != n || dead_.size() != n)
    in.fail("the saved air's particle arrays differ in length");
  if (n > settings_.maxParticles)
    in.fail(fmt::format("the saved air has {} particles, more than its limit {}", n, settings_.maxParticles));
  if (!std::isfinite(time_)) in.fail("the saved air's time is not finite");
  // Particles are inside the domain (those that left it are removed at the end of a step),
  // slower than any wind a scene can fill the air with (a step clamps them to the speed of
  // sound), within a hundred times the rest density, their pressure within 1e20 Pa, and their
  // obstacle normals unit or zero:
  // values beyond would overflow the forces.
  const Vec3 lo = settings_.domainMin - Vec3::Constant(h_), hi = settings_.domainMax + Vec3::Constant(h_);
  const float maxSpeed = std::max(1000.0f, settings_.soundSpeed), maxDensity = 100.0f * settings_.restDensity;
  for (size_t i = 0; i < n; ++i)
    if (!isFinite(x_[i]) || (x_[i].array() < lo.array()).any() || (x_[i].array() > hi.array()).any() ||
        !(v_[i].norm() <= maxSpeed) || !(rho_[i] > 0.0f && rho_[i] <= maxDensity) || !(std::abs(p_[i]) <= 1e20f) ||
        dead_[i] > 1 ||
        std::isnan(sdfBudget_[i]) || std::isnan(sdf_[i]) || !(sdfNormal_[i].squaredNorm() <= 1.01f))
      in.fail(fmt::format("the saved air's particle {} is damaged (a value out of range)", i));
  buildGrid();  // velocityAt samples the restored air, not the grid of the air before
}

}  // namespace tendril::wind

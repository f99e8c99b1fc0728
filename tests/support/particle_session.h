// The particle world behind a Session's particle plants, for tests and benchmarks that look at
// particles themselves (the library and the apps reach it only through models/capabilities.h).
#pragma once

#include "tendril/particles/particle_model.h"
#include "tendril/session/session.h"

namespace tendril::test {

// The session's particle world, or null when it has no particle plants.
inline particles::ParticleWorld* particleWorld(session::Session& s) {
  for (models::PlantSystem* system : s.systems())
    if (auto* p = dynamic_cast<particles::ParticlePlantSystem*>(system)) return &p->world();
  return nullptr;
}
inline const particles::ParticleWorld* particleWorld(const session::Session& s) {
  return particleWorld(const_cast<session::Session&>(s));
}

}  // namespace tendril::test

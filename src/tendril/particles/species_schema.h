// The particle species' own numbers described once (core/schema.h): the species reader reads
// them through it, the studio's species panel takes its labels, units and slider ranges from
// it, and a test keeps docs/particles.md's table in agreement. The nested "leaf", "bark" and
// "growth_flow" objects are read beside it (particles/species.cpp).
#pragma once

#include "tendril/core/schema.h"
#include "tendril/particles/species.h"

namespace tendril::particles {

const schema::Schema<ParticleSpecies>& particleSpeciesSchema();

}  // namespace tendril::particles

// The climbing species' numbers described once (core/schema.h): its own keys, those of its
// "tropisms" object and those of its "decrease" object. The species reader reads them through
// these descriptions, and a test keeps docs/species.md's tables in agreement with them. The
// angles (release_angle, branch_angle, the leaf's), "leaf", "bark", "growth_flow" and "rules"
// are read beside them (climb/species.cpp).
#pragma once

#include "tendril/climb/species.h"
#include "tendril/core/schema.h"

namespace tendril::climb {

const schema::Schema<ClimbSpecies>& climbSpeciesSchema();
const schema::Schema<ClimbSpecies>& climbTropismsSchema();
const schema::Schema<ClimbSpecies>& climbDecreaseSchema();

}  // namespace tendril::climb

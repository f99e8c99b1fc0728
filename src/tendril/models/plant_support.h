// A plant as a support for climbing plants of other models: its stems as round cones and its
// leaves as shade (env::Environment::setStems).
#pragma once

#include "tendril/env/environment.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <vector>

namespace tendril::models {

// Appends one tube per skeleton node of `plant` (from the node's start at its radius to its tip
// at the radius of the segment continuing it, or its own where none does) and one shade
// triangle per leaf blade. `plantIndex` goes into each tube's `plant`.
void appendSupport(const plant::PlantModel& plant, uint32_t plantIndex, std::vector<env::StemTube>& tubes,
                   std::vector<env::ShadeTriangle>& shade);

}  // namespace tendril::models

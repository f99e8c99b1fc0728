// PlantModels in binary archives (core/archive.h): session state of the models that keep
// their plants as PlantModels (climbing, graph).
#pragma once

#include "tendril/core/archive.h"
#include "tendril/plant/plant_model.h"

namespace tendril::plant {

void savePlantModel(ArchiveWriter& out, const PlantModel& plant);
// Throws Error (from the reader) for damaged input, including inconsistent array lengths and
// parents or leaf nodes out of range.
void loadPlantModel(ArchiveReader& in, PlantModel& plant);

}  // namespace tendril::plant

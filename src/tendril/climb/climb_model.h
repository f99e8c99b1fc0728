// The climbing model ("model": "climb") as seen by scenes and Sessions.
#pragma once

#include "tendril/climb/species.h"
#include "tendril/models/registry.h"

namespace tendril::climb {

struct ClimbParams : models::ModelParams {
  ClimbSpecies species;
};

models::ModelType climbModelType();

// Species presets compiled in from examples/species/*.json.
std::vector<std::string> builtinSpeciesNames();
// A species by built-in name or .json path (relative to baseDir); errors are located at
// (source, pointer).
ClimbSpecies loadSpecies(const std::string& nameOrPath, const std::filesystem::path& baseDir,
                         const std::string& source = "species", const std::string& pointer = "");

}  // namespace tendril::climb

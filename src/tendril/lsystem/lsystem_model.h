// The L-system model ("model": "lsystem") as seen by scenes and Sessions: a scene plant names
// a grammar (built-in or .ls file) and may override its define: constants; each Session step
// is one derivation step, with ?E queries answered by the scene's Environment.
#pragma once

#include "tendril/lsystem/grammar.h"
#include "tendril/models/registry.h"

#include <memory>
#include <optional>

namespace tendril::lsystem {

struct LSystemParams : models::ModelParams {
  std::shared_ptr<const Grammar> grammar;
  std::optional<int> derivationLength;  // "derivation_length": overrides the grammar's
  plant::GrowthFlowSpecies growthFlow;   // "growth_flow": how it grows in the wind (seed 001)
};

models::ModelType lsystemModelType();

}  // namespace tendril::lsystem

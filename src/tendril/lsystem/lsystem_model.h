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

class LSystem;

// A scene plant of this model, as the scene reader makes it of {"model": "lsystem", "grammar":
// ..., "define": ..., "derivation_length": ...}: the shared keys of `plant` (name, position,
// direction, seed) with `grammar` (already compiled with its defines) and the derivation length
// (none: the grammar's). For one-plant scenes (scene/one_plant_scene.h): `tendril lsys`, the
// studio's L-system preview.
models::PlantSpec lsystemPlant(models::PlantSpec plant, std::shared_ptr<const Grammar> grammar,
                              std::optional<int> derivationLength = std::nullopt);

// The derivation of plant `plant` (its index in the system) of an L-system model's system, or
// nullptr when `system` is another model's: its string, step count and globals.
const LSystem* derivationOf(const models::PlantSystem& system, size_t plant);

}  // namespace tendril::lsystem

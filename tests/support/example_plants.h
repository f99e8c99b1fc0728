// Example plants the io tests export, each built once per test binary.
#pragma once

#include "support/test_paths.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/plant/plant_model.h"

namespace tendril::test {

// Seed 004's chestnut (examples/graphs/chestnut.json: a component graph with leaves).
inline const plant::PlantModel& exampleChestnut() {
  static const plant::PlantModel p = [] {
    auto g = graph::loadGraph(sourceDir() / "examples/graphs/chestnut.json");
    return graph::generatePlant(g, {g->seed, {}});
  }();
  return p;
}

}  // namespace tendril::test

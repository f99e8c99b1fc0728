// Example plants the io tests export, each built once per test binary.
#pragma once

#include "support/test_paths.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/plant/plant_model.h"
#include "tendril/session/session.h"

#include <memory>

namespace tendril::test {

// Seed 004's chestnut (examples/graphs/chestnut.json: a component graph with leaves).
inline const plant::PlantModel& exampleChestnut() {
  static const plant::PlantModel p = [] {
    auto g = graph::loadGraph(sourceDir() / "examples/graphs/chestnut.json");
    return graph::generatePlant(g, {g->seed, {}});
  }();
  return p;
}

// The climbing ivy (seed 003) on the default scene's wall: examples/scenes/default.json after
// 160 steps, its second plant.
inline const plant::PlantModel& exampleClimbingIvy() {
  static const plant::PlantModel p = [] {
    std::unique_ptr<session::Session> s = session::Session::open(sourceDir() / "examples/scenes/default.json");
    s->run(160);
    return s->plants().at(1);
  }();
  return p;
}

}  // namespace tendril::test

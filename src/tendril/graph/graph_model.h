// Graph plants in scenes ("model": "graph"): a component graph placed at the plant's
// `position`, its +Y turned to `direction`.
//
// Scene keys read here: "graph" (the graph file, relative to the scene), "overrides" (an object
// of "component/parameter": value). The plant's "seed", when given, replaces the graph's. The
// plant is generated while the scene is read, so errors in the graph name the graph file (or
// the override in the scene) and its JSON pointer; it is static: its system is finished from
// the start and steps change nothing.
#pragma once

#include "tendril/graph/graph.h"
#include "tendril/models/registry.h"

#include <memory>

namespace tendril::graph {

struct GraphPlantParams : models::ModelParams {
  std::shared_ptr<const Graph> graph;
  std::shared_ptr<const plant::PlantModel> model;
};

models::ModelType graphModelType();

}  // namespace tendril::graph

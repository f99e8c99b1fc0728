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
  size_t instances = 0;  // component instances of the expanded i-tree (for reports)
};

models::ModelType graphModelType();

// A scene plant of this model, as the scene reader makes it of {"model": "graph", "graph": ...,
// "seed": plant.seed}: the shared keys of `plant` (name, position, direction, seed) with `graph`
// generated from that seed, standing at the position, +Y turned to the direction. For one-plant
// scenes (scene/one_plant_scene.h): `tendril model`.
models::PlantSpec graphPlant(models::PlantSpec plant, std::shared_ptr<const Graph> graph);

}  // namespace tendril::graph

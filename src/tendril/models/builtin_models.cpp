// The table of growth models. One entry per model; each model's reader and system live in its
// own module.
#include "tendril/climb/climb_model.h"
#include "tendril/graph/graph_model.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/models/registry.h"
#include "tendril/particles/particle_model.h"

namespace tendril::models {

std::span<const ModelType> modelTypes() {
  static const ModelType kTypes[] = {
      climb::climbModelType(),
      graph::graphModelType(),
      particles::particleModelType(),
      lsystem::lsystemModelType(),
  };
  return kTypes;
}

const ModelType* findModelType(std::string_view name) {
  for (const ModelType& t : modelTypes())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace tendril::models

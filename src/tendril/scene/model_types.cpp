#include "tendril/scene/model_types.h"

// Each model's reader and system live in its own module; this is the one place that names them.
#include "tendril/climb/climb_model.h"
#include "tendril/graph/graph_model.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/particles/particle_model.h"

namespace tendril::scene {

std::span<const models::ModelType> modelTypes() {
  static const models::ModelType kTypes[] = {
      climb::climbModelType(),
      graph::graphModelType(),
      particles::particleModelType(),
      lsystem::lsystemModelType(),
  };
  return kTypes;
}

const models::ModelType* findModelType(std::string_view name) {
  for (const models::ModelType& t : modelTypes())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace tendril::scene

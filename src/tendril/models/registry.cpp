#include "tendril/models/registry.h"

#include "tendril/core/error.h"

namespace tendril::models {

PlantSystem::~PlantSystem() = default;

std::vector<plant::PlantModel> PlantSystem::snapshots() const {
  std::vector<plant::PlantModel> out;
  out.reserve(plantCount());
  for (size_t i = 0; i < plantCount(); ++i) out.push_back(snapshot(i));
  return out;
}

void PlantSystem::setParams(size_t /*plant*/, const PlantSpec& spec) {
  throw Error("", "", "plants of model \"" + spec.model + "\" cannot change their settings while growing");
}

void PlantSystem::cut(size_t /*plant*/, uint32_t /*node*/, bool /*remove*/) { throw Error("", "", "plants of this model cannot be cut"); }

}  // namespace tendril::models

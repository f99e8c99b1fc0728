// One plant of a scene, as read from the file: the keys every growth model shares, and the
// model's own settings parsed by that model's reader (see models/registry.h).
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <memory>
#include <string>

namespace tendril::models {

// Model-specific settings of one plant (a climbing species, a grammar, a component graph...).
struct ModelParams {
  virtual ~ModelParams() = default;
};

struct PlantSpec {
  std::string name;
  std::string model = "climb";  // growth model, a name in scene::modelTypes()
  std::string pointer;          // JSON pointer of the plant in the scene file, for messages
  Vec3 position = Vec3::Zero();   // seed point (m)
  Vec3 direction = Vec3::UnitY(); // initial growth direction
  uint64_t seed = 1;              // the plant's own random seed
  bool support = false;           // its stems hold climbing plants of other models, its leaves shade them
  std::shared_ptr<const ModelParams> params;

  // The settings as the model's own type (nullptr if they are of another model).
  template <class T>
  const T* paramsAs() const {
    return dynamic_cast<const T*>(params.get());
  }
};

}  // namespace tendril::models

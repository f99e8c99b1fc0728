// The table of growth models a scene can name ("model" of a scene plant). It sits above the
// models (it names each of them) and below the scene reader and the Session, its users.
#pragma once

#include "tendril/models/registry.h"

#include <span>
#include <string_view>

namespace tendril::scene {

// Every built-in model, in a fixed order (climb, graph, particles, lsystem).
std::span<const models::ModelType> modelTypes();
// The model of that name, or null.
const models::ModelType* findModelType(std::string_view name);

}  // namespace tendril::scene

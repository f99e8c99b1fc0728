// Reading the leaf-shape and bark keys that every model's species files share.
#pragma once

#include "tendril/plant/plant_model.h"

#include <string>
#include <vector>

namespace tendril {
class JsonObject;
}

namespace tendril::plant {

// A texture reference as written in a species file: "builtin:..." and absolute paths as they
// are, other paths relative to `baseDir` (the file's folder; "" for built-in species).
std::string resolveTexturePath(const std::string& spec, const std::string& baseDir);

// The "textures" (replacing the shapes), "aspect" and "tint" keys of a species' "leaf" object;
// absent keys keep the shapes' values. Other keys of `leaf` are the caller's.
void readLeafShapes(JsonObject& leaf, std::vector<LeafShape>& shapes, const std::string& baseDir);

// A species' "bark" object (texture, color, roughness), finished.
void readBark(JsonObject& bark, BarkMaterial& material, const std::string& baseDir);

}  // namespace tendril::plant

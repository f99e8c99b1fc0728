#include "tendril/plant/species_materials.h"

#include "tendril/core/json_reader.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace tendril::plant {

std::string resolveTexturePath(const std::string& spec, const std::string& baseDir) {
  if (spec.rfind("builtin:", 0) == 0 || baseDir.empty()) return spec;
  std::filesystem::path p(spec);
  if (p.is_absolute()) return spec;
  return (std::filesystem::path(baseDir) / p).lexically_normal().string();
}

void readLeafShapes(JsonObject& l, std::vector<LeafShape>& shapes, const std::string& baseDir) {
  const float aspect = l.numberf("aspect", shapes.empty() ? 1.0f : shapes[0].aspect, 0.05, 20.0);
  if (const Json* tex = l.find("textures")) {
    if (!tex->is_array() || tex->empty())
      throw l.error("textures", "expected a non-empty array of texture names or image paths");
    const Vec3 tint = l.vec3("tint", Vec3::Ones(), 0.0, 10.0);
    shapes.clear();
    for (size_t i = 0; i < tex->size(); ++i) {
      if (!(*tex)[i].is_string())
        throw Error(l.source(), l.pointerTo("textures") + "/" + std::to_string(i),
                    "expected a string, got " + describeJson((*tex)[i]));
      shapes.push_back({resolveTexturePath((*tex)[i].get<std::string>(), baseDir), aspect, tint});
    }
  } else {
    const Vec3 tint = l.vec3("tint", shapes.empty() ? Vec3::Ones() : shapes[0].tint, 0.0, 10.0);
    for (LeafShape& shape : shapes) {
      shape.aspect = aspect;
      shape.tint = tint;
    }
  }
}

void readBark(JsonObject& b, BarkMaterial& material, const std::string& baseDir) {
  material.texture = resolveTexturePath(b.string("texture", material.texture), baseDir);
  material.color = b.vec3("color", material.color, 0.0, 1.0);
  material.roughness = b.numberf("roughness", material.roughness, 0.0, 1.0);
  b.finish();
}

}  // namespace tendril::plant

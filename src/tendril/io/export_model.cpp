#include "tendril/io/export_model.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/io/material_maps.h"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <exception>
#include <filesystem>

#include <tbb/parallel_invoke.h>

namespace tendril::io {
namespace {

using Kind = ExportMaterial::Kind;

// glTF needs colour factors in [0, 1]; NaN (which no clamp removes) is an Error.
Vec4 clampedColor(const Vec3& rgb, const std::string& source, const std::string& what) {
  if (!isFinite(rgb))
    throw Error(source, what, fmt::format("colour must be finite, got ({}, {}, {})", rgb.x(), rgb.y(), rgb.z()));
  Vec3 c = rgb.cwiseMax(0.0f).cwiseMin(1.0f);
  return Vec4(c.x(), c.y(), c.z(), 1.0f);
}

float clamp01(float v) { return std::min(1.0f, std::max(0.0f, v)); }

// A readable name for a texture spec: "ivy-0" for builtin:ivy-0, the file's stem otherwise.
std::string textureLabel(const std::string& spec) {
  if (isBuiltinTexture(spec)) return spec.substr(kBuiltinPrefix.size());
  return std::filesystem::path(spec).stem().string();
}

// Every texture spec the scene's plants may use, each once, in order of first use.
std::vector<std::string> textureSpecs(const ExportScene& scene) {
  std::vector<std::string> specs;
  auto add = [&](const std::string& spec) {
    if (!spec.empty() && std::find(specs.begin(), specs.end(), spec) == specs.end()) specs.push_back(spec);
  };
  for (const plant::PlantModel& p : scene.plants) {
    if (p.nodeCount() > 0) add(p.bark.texture);
    std::vector<uint8_t> used(mesh::leafShapeCount(p), 0);
    for (uint16_t s : p.leafShape) used[s] = 1;
    for (size_t s = 0; s < used.size(); ++s)
      if (used[s]) add(mesh::leafShapeFor(p, s).texture);
    for (const plant::Primitive& pr : p.primitives)
      if (pr.mesh < p.meshes.size()) add(p.meshes[pr.mesh].texture);
  }
  return specs;
}

class ModelBuilder {
 public:
  ModelBuilder(ExportModel& model, std::vector<std::string>& specs, std::vector<EncodedImage>& loaded,
               std::vector<std::exception_ptr>& failed)
      : model_(model), specs_(specs), loaded_(loaded), failed_(failed) {}

  int texture(const std::string& spec, bool repeat) {
    int image = -1;
    for (size_t i = 0; i < model_.images.size(); ++i)
      if (model_.images[i].spec == spec) image = static_cast<int>(i);
    if (image < 0) {
      auto it = std::find(specs_.begin(), specs_.end(), spec);
      if (it == specs_.end()) {
        model_.images.push_back({spec, loadEncodedTexture(spec)});
      } else {
        size_t k = static_cast<size_t>(it - specs_.begin());
        if (failed_[k]) std::rethrow_exception(failed_[k]);  // reported where first used
        model_.images.push_back({spec, std::move(loaded_[k])});
      }
      image = static_cast<int>(model_.images.size() - 1);
    }
    for (size_t t = 0; t < model_.textures.size(); ++t)
      if (model_.textures[t].image == image && model_.textures[t].repeat == repeat) return static_cast<int>(t);
    model_.textures.push_back({image, repeat});
    return static_cast<int>(model_.textures.size() - 1);
  }

  // The clamped texture of a leaf atlas (its image taken from the atlas on first use).
  int atlasTexture(const std::string& spec, EncodedImage& encoded) {
    int image = -1;
    for (size_t i = 0; i < model_.images.size(); ++i)
      if (model_.images[i].spec == spec) image = static_cast<int>(i);
    if (image < 0) {
      model_.images.push_back({spec, std::move(encoded)});
      image = static_cast<int>(model_.images.size() - 1);
    }
    for (size_t t = 0; t < model_.textures.size(); ++t)
      if (model_.textures[t].image == image && !model_.textures[t].repeat) return static_cast<int>(t);
    model_.textures.push_back({image, false});
    return static_cast<int>(model_.textures.size() - 1);
  }

  // A map made from the image of texture `colour` (already in the model): "<spec>#normal" or
  // "<spec>#roughness", made once (io/material_maps.h), with the colour texture's wrap mode.
  int mapTexture(int colour, bool normal, float reliefPixels) {
    const ExportTexture t = model_.textures[size_t(colour)];
    const std::string spec = model_.images[size_t(t.image)].spec;
    const std::string mapSpec = spec + (normal ? "#normal" : "#roughness");
    int image = -1;
    for (size_t i = 0; i < model_.images.size(); ++i)
      if (model_.images[i].spec == mapSpec) image = static_cast<int>(i);
    if (image < 0) {
      const EncodedImage& encoded = model_.images[size_t(t.image)].image;
      const HeightField field = spec == "builtin:bark" ? barkHeightField(encoded.width)
                                                       : luminanceHeightField(decodeImage(encoded.bytes, spec));
      const Image map = normal ? normalMap(field, reliefPixels, t.repeat) : roughnessMap(field);
      model_.images.push_back({mapSpec, {"image/png", encodePng(map), map.width, map.height}});
      image = static_cast<int>(model_.images.size() - 1);
    }
    for (size_t k = 0; k < model_.textures.size(); ++k)
      if (model_.textures[k].image == image && model_.textures[k].repeat == t.repeat) return static_cast<int>(k);
    model_.textures.push_back({image, t.repeat});
    return static_cast<int>(model_.textures.size() - 1);
  }

  // The index of an equal material, or of `m` added under a unique version of its name.
  int material(ExportMaterial m) {
    for (size_t i = 0; i < model_.materials.size(); ++i) {
      const ExportMaterial& o = model_.materials[i];
      if (o.kind == m.kind && o.texture == m.texture && o.baseColor == m.baseColor && o.roughness == m.roughness &&
          o.metallic == m.metallic && o.alphaMask == m.alphaMask && o.doubleSided == m.doubleSided &&
          o.diffuseTransmission == m.diffuseTransmission && o.normalTexture == m.normalTexture &&
          o.roughnessTexture == m.roughnessTexture)
        return static_cast<int>(i);
    }
    std::string base = m.name;
    for (int k = 2; nameTaken(m.name); ++k) m.name = fmt::format("{}-{}", base, k);
    model_.materials.push_back(std::move(m));
    return static_cast<int>(model_.materials.size() - 1);
  }

 private:
  bool nameTaken(const std::string& name) const {
    return std::any_of(model_.materials.begin(), model_.materials.end(),
                       [&](const ExportMaterial& o) { return o.name == name; });
  }
  ExportModel& model_;
  std::vector<std::string>& specs_;     // preloaded textures ...
  std::vector<EncodedImage>& loaded_;  // ... moved out on first use
  std::vector<std::exception_ptr>& failed_;
};

// Obstacles and other extra meshes: checked, with unit normals.
TriangleMesh preparedMesh(const NamedMesh& named) {
  const TriangleMesh& m = named.mesh;
  auto bad = [&](const std::string& what) { return Error(fmt::format("mesh \"{}\"", named.name), "", what); };
  if (m.indices.size() % 3 != 0) throw bad("index count is not a multiple of 3");
  for (uint32_t i : m.indices)
    if (i >= m.positions.size()) throw bad("index out of range");
  for (const Vec3& p : m.positions)
    if (!isFinite(p)) throw bad("position is not finite");
  if (!m.normals.empty() && m.normals.size() != m.positions.size()) throw bad("normal count differs from vertex count");
  if (!m.uvs.empty() && m.uvs.size() != m.positions.size()) throw bad("uv count differs from vertex count");
  TriangleMesh out = m;
  bool unitNormals = !out.normals.empty() && std::all_of(out.normals.begin(), out.normals.end(), [](const Vec3& n) {
    return std::abs(n.squaredNorm() - 1.0f) < 1e-3f;
  });
  if (!unitNormals) out.computeNormals();
  return out;
}

}  // namespace

std::string levelName(const ExportObject& object, size_t level) {
  return object.lods.empty() ? object.name : fmt::format("{}_LOD{}", object.name, level);
}

void meshPlantLevels(const plant::PlantModel& plant, const ExportOptions& options, mesh::PlantMesh& mesh,
                     std::vector<mesh::LodLevel>& lods) {
  mesh::buildPlantMesh(plant, options.mesh, mesh);
  if (options.lods.levels <= 1 || mesh.triangleCount() == 0) {
    lods.clear();
    return;
  }
  mesh::buildLods(plant, options.mesh, mesh, options.lods, lods);
  mesh::optimizeMeshOrder(mesh);
}

std::vector<std::string> lodBudgetWarnings(const plant::PlantModel& plant, size_t index,
                                           const std::vector<mesh::LodLevel>& lods) {
  std::vector<std::string> warnings;
  for (size_t k = 0; k < lods.size(); ++k)
    if (lods[k].overBudget())
      warnings.push_back(fmt::format(
          "plant \"{}\": LOD{} has {} triangles, over its budget of {} (the fewest it could be brought to, with {} "
          "leaves and {} radial segments; written as it is)",
          plant.name.empty() ? fmt::format("plant-{}", index) : plant.name, k + 1, lods[k].triangles, lods[k].budget,
          lods[k].leaves, lods[k].options.radialSegments));
  return warnings;
}

PlantParts plantParts(const mesh::PlantMesh& mesh, const std::vector<mesh::LodLevel>& lods) {
  PlantParts parts = plantParts(mesh);
  if (lods.empty()) return parts;
  parts.levelTriangles.push_back(mesh.triangleCount());
  for (const mesh::LodLevel& level : lods) {
    parts.lods.push_back(plantParts(level.mesh));
    parts.levelTriangles.push_back(level.triangles);
  }
  return parts;
}

void addInstancing(PlantParts& parts, const PlantInstancing& instancing) {
  parts.primitiveInstancing = instancing.instanced;
  parts.instancedShapes.clear();
  for (const InstancedShape& s : instancing.shapes) parts.instancedShapes.emplace_back(s.group, s.name);
}

PlantInstancing plantInstancing(const ExportScene& scene, size_t index, const ExportOptions& options,
                                const mesh::PlantMesh& mesh) {
  if (!options.instancing) return {};
  InstancingCost cost;
  cost.wind = index < scene.wind.size() && !scene.wind[index].empty();
  cost.cacheOrder = options.lods.levels > 1 && mesh.triangleCount() > 0;  // as meshPlantLevels orders LOD0
  return instancePrimitives(scene.plants[index], mesh.primitives, cost);
}

PlantParts plantParts(const mesh::PlantMesh& mesh) {
  PlantParts parts;
  parts.bark = !mesh.bark.empty();
  for (const TriangleMesh& m : mesh.leaves) parts.leaves.push_back(m.empty() ? 0 : 1);
  for (const mesh::PrimitiveGroup& g : mesh.primitives) {
    parts.primitives.push_back({g.name, g.color, g.texture, {}});
    parts.primitiveTriangles.push_back(g.mesh.empty() ? 0 : 1);
  }
  return parts;
}

TexturePreload preloadTextures(const ExportScene& scene) {
  TexturePreload t;
  t.specs = textureSpecs(scene);
  t.loaded.resize(t.specs.size());
  t.failed.resize(t.specs.size());
  parallelFor(0, t.specs.size(), [&](size_t i) {
    try {
      t.loaded[i] = loadEncodedTexture(t.specs[i]);
    } catch (...) {
      t.failed[i] = std::current_exception();
    }
  }, 1);
  return t;
}

ExportModel assembleExportModel(const ExportScene& scene, const std::vector<PlantParts>& parts,
                                TexturePreload& textures, LeafAtlases* atlases, bool maps) {
  assert(parts.size() == scene.plants.size());
  assert(!atlases || atlases->plants.size() == scene.plants.size());
  ExportModel model;
  model.extraMeshes.reserve(scene.meshes.size());
  for (const NamedMesh& m : scene.meshes) model.extraMeshes.push_back(preparedMesh(m));

  // Materials and textures are created when a non-empty part needs them, so that nothing in
  // the file is unused.
  ModelBuilder builder(model, textures.specs, textures.loaded, textures.failed);
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    const plant::PlantModel& p = scene.plants[i];
    const PlantParts& pm = parts[i];
    ExportObject object;
    object.name = p.name.empty() ? fmt::format("plant-{}", i) : p.name;
    if (pm.bark) {
      ExportMaterial m;
      m.kind = Kind::Bark;
      m.name = "bark";
      if (!std::isfinite(p.bark.roughness))
        throw Error(object.name, "bark", fmt::format("roughness must be finite, got {}", p.bark.roughness));
      m.roughness = clamp01(p.bark.roughness);
      if (p.bark.texture.empty()) {
        m.baseColor = clampedColor(p.bark.color, object.name, "bark");
      } else {
        m.texture = builder.texture(p.bark.texture, true);  // the texture carries the colour
        if (maps) {
          m.normalTexture = builder.mapTexture(m.texture, true, kBarkReliefPixels);
          m.roughnessTexture = builder.mapTexture(m.texture, false, 0.0f);
        }
      }
      object.parts.push_back({"bark", nullptr, builder.material(std::move(m)), PartSource::Bark, 0});
    }
    const PlantLeafAtlas* leafAtlas = atlases && atlases->plants[i].atlas >= 0 ? &atlases->plants[i] : nullptr;
    for (size_t s = 0; s < pm.leaves.size(); ++s) {
      if (!pm.leaves[s]) continue;
      if (leafAtlas) {
        // Every leaf, in the atlas's one material.
        LeafAtlas& atlas = atlases->atlases[size_t(leafAtlas->atlas)];
        ExportMaterial m;
        m.kind = Kind::Leaf;
        m.name = "leaf-atlas";
        m.baseColor = Vec4(atlas.tint.x(), atlas.tint.y(), atlas.tint.z(), 1.0f);
        m.roughness = 0.5f;
        m.texture = builder.atlasTexture(atlas.spec, atlas.image);
        // The atlas's normal map: made from the atlas, so it has the same rectangles.
        if (maps) m.normalTexture = builder.mapTexture(m.texture, true, kLeafReliefPixels);
        m.alphaMask = true;
        m.doubleSided = true;
        m.diffuseTransmission = kLeafDiffuseTransmission;
        object.parts.push_back({"leaves", nullptr, builder.material(std::move(m)), PartSource::Leaves, uint32_t(s)});
        continue;
      }
      plant::LeafShape shape = mesh::leafShapeFor(p, s);
      ExportMaterial m;
      m.kind = Kind::Leaf;
      m.name = "leaf-" + textureLabel(shape.texture);
      m.baseColor = clampedColor(shape.tint, object.name, fmt::format("leaf shape {}", s));
      m.roughness = 0.5f;  // a glossy cuticle
      m.texture = builder.texture(shape.texture, false);
      if (maps) m.normalTexture = builder.mapTexture(m.texture, true, kLeafReliefPixels);
      m.alphaMask = true;
      m.doubleSided = true;
      object.parts.push_back({fmt::format("leaves-{}", s), nullptr, builder.material(std::move(m)),
                              PartSource::Leaves, uint32_t(s)});
    }
    for (size_t k = 0; k < pm.primitives.size(); ++k) {
      if (!pm.primitiveTriangles[k]) continue;
      const mesh::PrimitiveGroup& g = pm.primitives[k];
      ExportMaterial m;
      m.name = g.name.empty() ? std::string("primitive") : g.name;
      m.baseColor = clampedColor(g.color, object.name, "primitive " + m.name);
      m.roughness = 0.8f;
      if (!g.texture.empty()) m.texture = builder.texture(g.texture, true);
      std::string name = m.name;
      object.parts.push_back({name, nullptr, builder.material(std::move(m)), PartSource::Primitive, uint32_t(k)});
      if (k < pm.primitiveInstancing.size()) object.parts.back().instancing = pm.primitiveInstancing[k];
    }
    // Instanced shapes, in their primitive group's material.
    for (const auto& [group, name] : pm.instancedShapes)
      for (const ExportPart& part : object.parts)
        if (part.source == PartSource::Primitive && part.index == group)
          object.instanced.push_back({name, part.material, group, nullptr});
    // Lower levels: the parts of LOD0 that still have triangles there, with LOD0's materials.
    for (const PlantParts& level : pm.lods) {
      std::vector<ExportPart>& lodParts = object.lods.emplace_back();
      for (const ExportPart& part : object.parts) {
        const bool has = part.source == PartSource::Bark     ? level.bark
                         : part.source == PartSource::Leaves ? part.index < level.leaves.size() && level.leaves[part.index]
                                                             : part.index < level.primitiveTriangles.size() &&
                                                                   level.primitiveTriangles[part.index];
        if (has) {
          lodParts.push_back(part);
          lodParts.back().instancing = 0;  // lower levels are baked (io/instancing.h)
        }
      }
    }
    if (!pm.lods.empty()) object.screenCoverage = mesh::lodScreenCoverage(pm.levelTriangles);
    model.objects.push_back(std::move(object));
  }
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const NamedMesh& n = scene.meshes[i];
    ExportObject object;
    object.name = n.name.empty() ? fmt::format("mesh-{}", i) : n.name;
    if (!model.extraMeshes[i].empty()) {
      ExportMaterial m;
      m.name = object.name;
      m.baseColor = clampedColor(n.color, object.name, "colour");
      m.roughness = 0.8f;
      object.parts.push_back({object.name, &model.extraMeshes[i], builder.material(std::move(m)), PartSource::Mesh,
                              uint32_t(i)});
    }
    model.objects.push_back(std::move(object));
  }
  return model;
}

ExportModel buildExportModel(const ExportScene& scene, const ExportOptions& options) {
  // Textures load (or are generated) while the plants are meshed: both take a while for a
  // large scene and neither needs the other.
  mesh::validateLodSettings(options.lods, "export options");
  impostorBakerFor(options);  // no baker: an error before the work
  std::vector<mesh::PlantMesh> meshes;
  std::vector<std::vector<mesh::LodLevel>> lods;
  TexturePreload textures;
  tbb::parallel_invoke(
      [&] {
        // Plants are meshed in parallel too: a climbing scene is hundreds of plants of a
        // thousand segments, too small for the sweep's own parallel loops to keep both cores
        // busy. Each mesh depends on its plant only; the first failing plant (by index) is
        // the one reported, as when they were meshed in order.
        const size_t n = scene.plants.size();
        meshes.resize(n);
        lods.resize(n);
        std::vector<std::exception_ptr> meshFailed(n);
        parallelFor(0, n, [&](size_t i) {
          try {
            meshPlantLevels(scene.plants[i], options, meshes[i], lods[i]);
          } catch (...) {
            meshFailed[i] = std::current_exception();
          }
        }, 1);
        for (const std::exception_ptr& e : meshFailed)
          if (e) std::rethrow_exception(e);
      },
      [&] { textures = preloadTextures(scene); });
  LeafAtlases atlases;
  if (options.leafAtlas) {
    atlases = buildLeafAtlases(scene, textures);
    parallelFor(0, meshes.size(), [&](size_t i) {
      applyLeafAtlas(atlases, atlases.plants[i], meshes[i]);
      for (mesh::LodLevel& level : lods[i]) applyLeafAtlas(atlases, atlases.plants[i], level.mesh);
    }, 1);
  }
  std::vector<PlantInstancing> instancing(meshes.size());
  if (options.instancing)
    parallelFor(0, meshes.size(), [&](size_t i) { instancing[i] = plantInstancing(scene, i, options, meshes[i]); }, 1);
  std::vector<PlantParts> parts;
  parts.reserve(meshes.size());
  for (size_t i = 0; i < meshes.size(); ++i) {
    parts.push_back(plantParts(meshes[i], lods[i]));
    addInstancing(parts.back(), instancing[i]);
    for (const std::string& w : lodBudgetWarnings(scene.plants[i], i, lods[i])) log::warn("{}", w);
  }
  ExportModel model = assembleExportModel(scene, parts, textures, options.leafAtlas ? &atlases : nullptr, options.maps);
  model.leafAtlases = std::move(atlases);
  model.plantMeshes = std::move(meshes);
  model.plantLods = std::move(lods);
  model.plantInstancing = std::move(instancing);
  auto meshOf = [](const mesh::PlantMesh& pm, const ExportPart& part) {
    return part.source == PartSource::Bark     ? &pm.bark
           : part.source == PartSource::Leaves ? &pm.leaves[part.index]
                                               : &pm.primitives[part.index].mesh;
  };
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    ExportObject& object = model.objects[i];
    for (ExportPart& part : object.parts) {
      part.mesh = meshOf(model.plantMeshes[i], part);
      if (part.instancing == 1) part.rest = &model.plantInstancing[i].rest[part.index];
    }
    for (size_t k = 0; k < object.instanced.size(); ++k) object.instanced[k].shape = &model.plantInstancing[i].shapes[k];
    for (size_t k = 0; k < object.lods.size(); ++k)
      for (ExportPart& part : object.lods[k]) part.mesh = meshOf(model.plantLods[i][k].mesh, part);
    // Normal-mapped parts, on every level, carry their tangents (glTF TANGENT; the validator warns about
    // tangent spaces left to the reader, which need not agree between readers).
    if (options.maps)
      for (size_t level = 0; level < object.levels(); ++level)
        for (ExportPart& part : level == 0 ? object.parts : object.lods[level - 1]) {
          const ExportMaterial& m = model.materials[size_t(part.material)];
          if (m.normalTexture < 0 || !part.mesh || part.mesh->uvs.empty() || part.mesh->normals.empty()) continue;
          model.mapTangents.push_back(std::make_unique<std::vector<Vec4>>(computeTangents(*part.mesh)));
          part.tangents = model.mapTangents.back().get();
        }
  }
  addImpostors(scene, options, model);
  return model;
}

}  // namespace tendril::io

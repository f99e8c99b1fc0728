// The step both exporters share: mesh every plant (in parallel), load each texture once and
// give every part a material. Textures and materials are shared between plants when they are
// the same (same image spec; same kind, texture and factors).
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/io/instancing.h"
#include "tendril/io/leaf_atlas.h"
#include "tendril/io/texture.h"
#include "tendril/mesh/plant_mesh.h"

#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace tendril::io {

struct ExportImage {
  std::string spec;  // "builtin:bark", a file path, ...
  EncodedImage image;
};

struct ExportTexture {
  int image = 0;        // index into ExportModel::images
  bool repeat = false;  // wrap (bark, primitives) or clamp to edge (leaves)
};

struct ExportMaterial {
  enum class Kind { Bark, Leaf, Plain, Impostor };
  Kind kind = Kind::Plain;
  std::string name;
  Vec4 baseColor = Vec4::Ones();  // linear RGBA factor, in [0, 1]
  float roughness = 1.0f;
  float metallic = 0.0f;
  int texture = -1;                // index into ExportModel::textures
  int normalTexture = -1;          // a tangent-space normal map (impostors), index into textures
  // With ExportOptions::maps: roughness in G, metal 0 in B (glTF metallicRoughnessTexture; bark).
  int roughnessTexture = -1;
  bool alphaMask = false;          // leaves: cut out where texture alpha < 0.5
  bool doubleSided = false;
  // KHR_materials_diffuse_transmission: the share of diffuse light let through (leaf atlases'
  // leaves, lit from behind), coloured by the base colour texture; 0: none.
  float diffuseTransmission = 0.0f;
};

// Where a part's triangles come from: its object's plant mesh (bark, the leaves of one shape,
// one primitive group) or, for an extra mesh's object, that mesh.
enum class PartSource : uint8_t { Bark, Leaves, Primitive, Mesh };

struct ExportPart {
  std::string name;            // "bark", "leaves-0", a primitive or mesh name
  const TriangleMesh* mesh = nullptr;  // points into ExportModel; never empty (null in an assembled model)
  int material = 0;
  PartSource source = PartSource::Mesh;
  uint32_t index = 0;  // leaf shape id (Leaves) or primitive group (Primitive)
  // Per vertex xyz the tangent along +U, w the bitangent's sign (glTF TANGENT): impostor quads.
  const std::vector<Vec4>* tangents = nullptr;
  // GPU instancing (LOD0 primitive parts; ExportObject::instanced): 0 the .glb bakes `mesh`;
  // 1 some of the group's primitives are instances and the .glb bakes the others, `rest`
  // (null in an assembled model); 2 all are, and the .glb has no such part. The .obj bakes `mesh`.
  uint8_t instancing = 0;
  const TriangleMesh* rest = nullptr;
};

// A primitive shape written once and drawn at each of its copies (EXT_mesh_gpu_instancing).
struct ExportInstanced {
  std::string name;  // the shape's (its primitive mesh's) name
  int material = 0;  // its primitive group's
  uint32_t group = 0;
  const InstancedShape* shape = nullptr;  // points into ExportModel; null in an assembled model
};

struct ExportObject {
  std::string name;  // the plant's (or extra mesh's) name
  std::vector<ExportPart> parts;
  // A plant written with levels of detail: the parts of LOD1, LOD2, ... (each a subset of
  // `parts`, with the same materials) and, per level from LOD0, the screen coverage below which
  // it gives way to the next (mesh::lodScreenCoverage). Empty without a LOD chain.
  std::vector<std::vector<ExportPart>> lods;
  std::vector<float> screenCoverage;
  // With ExportOptions::instancing: LOD0's instanced primitive shapes (a node each, under LOD0's).
  std::vector<ExportInstanced> instanced;

  size_t levels() const { return 1 + lods.size(); }
  const std::vector<ExportPart>& partsOf(size_t level) const { return level == 0 ? parts : lods[level - 1]; }
};

// The name of an object's level: "<name>_LOD<level>" when it has levels of detail (what game
// engines' importers look for), else its name.
std::string levelName(const ExportObject& object, size_t level);

// Parts point into the model's own meshes: move it, do not copy it.
struct ExportModel {
  ExportModel() = default;
  ExportModel(ExportModel&&) = default;
  ExportModel& operator=(ExportModel&&) = default;
  ExportModel(const ExportModel&) = delete;
  ExportModel& operator=(const ExportModel&) = delete;

  std::vector<mesh::PlantMesh> plantMeshes;  // one per scene plant
  std::vector<std::vector<mesh::LodLevel>> plantLods;  // per scene plant: LOD1, LOD2, ... (none without a chain)
  std::vector<TriangleMesh> extraMeshes;     // scene meshes with normals ensured
  std::vector<ExportObject> objects;         // plants, then extra meshes
  std::vector<ExportMaterial> materials;
  std::vector<ExportTexture> textures;
  std::vector<ExportImage> images;
  // With ExportOptions::leafAtlas: each plant's atlas layout (its image moved into `images`).
  LeafAtlases leafAtlases;
  // With ExportOptions::impostor: per scene plant its impostor (its object's last level, its
  // atlas images moved into `images`). Empty otherwise.
  std::vector<Impostor> impostors;
  // With ExportOptions::instancing: per scene plant, its LOD0 primitives' instancing (empty: none).
  std::vector<PlantInstancing> plantInstancing;
  // With ExportOptions::maps: the TANGENT arrays of the parts whose material has a normal map
  // (ExportPart::tangents points here; io/material_maps.h computeTangents).
  std::vector<std::unique_ptr<std::vector<Vec4>>> mapTangents;
};

// Throws Error for invalid plants or options and for textures that cannot be read. Levels
// over their triangle budget are warned about (lodBudgetWarnings).
ExportModel buildExportModel(const ExportScene& scene, const ExportOptions& options);

// With ExportOptions::impostor: the installed baker (an Error when there is none, or the
// settings are out of range); null without.
std::shared_ptr<ImpostorBaker> impostorBakerFor(const ExportOptions& options);
// Bakes each plant's impostor (from its LOD0 parts, as `model` has them) and adds it as its
// object's last level, with its material, textures and images (nothing without the option).
void addImpostors(const ExportScene& scene, const ExportOptions& options, ExportModel& model);

// Meshes one plant as the exporters do: LOD0 into `mesh` and, with a LOD chain, its lower levels
// into `lods` (then every level in vertex cache and fetch order).
void meshPlantLevels(const plant::PlantModel& plant, const ExportOptions& options, mesh::PlantMesh& mesh,
                     std::vector<mesh::LodLevel>& lods);
// A warning for each level of plant `index` over its triangle budget (such a level is written
// with the fewest triangles reached); the exporters log them, in plant order, on the calling
// thread.
std::vector<std::string> lodBudgetWarnings(const plant::PlantModel& plant, size_t index,
                                           const std::vector<mesh::LodLevel>& lods);

// What the objects, parts and materials depend on of a plant's meshes: which parts have
// triangles (their geometry is not needed).
struct PlantParts {
  bool bark = false;
  std::vector<uint8_t> leaves;                   // per leaf shape id: 1 if it has triangles
  std::vector<mesh::PrimitiveGroup> primitives;  // name, colour and texture (meshes left empty)
  std::vector<uint8_t> primitiveTriangles;       // per group: 1 if it has triangles
  // With levels of detail: the same of LOD1, LOD2, ... and every level's triangle count.
  std::vector<PlantParts> lods;
  std::vector<size_t> levelTriangles;
  // With instancing (LOD0): per primitive group PlantInstancing::instanced, and the instanced
  // shapes' groups and names in file order.
  std::vector<uint8_t> primitiveInstancing;
  std::vector<std::pair<uint32_t, std::string>> instancedShapes;
};
PlantParts plantParts(const mesh::PlantMesh& mesh);
PlantParts plantParts(const mesh::PlantMesh& mesh, const std::vector<mesh::LodLevel>& lods);
// Records a plant's instancing in its parts.
void addInstancing(PlantParts& parts, const PlantInstancing& instancing);
// The instancing the exporters give plant `index` of `scene` meshed as `mesh` (LOD0) with
// `options` (none without ExportOptions::instancing).
PlantInstancing plantInstancing(const ExportScene& scene, size_t index, const ExportOptions& options,
                                const mesh::PlantMesh& mesh);

// The textures a scene's plants use, loaded in parallel ahead of the model that needs them; a
// texture that fails is reported when a part first uses it.
struct TexturePreload {
  std::vector<std::string> specs;
  std::vector<EncodedImage> loaded;
  std::vector<std::exception_ptr> failed;
};
TexturePreload preloadTextures(const ExportScene& scene);

// Materials, textures, images, extra meshes and objects for a scene whose plants' meshes have
// `parts` (one per plant), as buildExportModel makes them, but without plant meshes: parts of
// plants have a null `mesh` (the streaming .glb writer meshes plants one at a time and keeps
// none). Takes the preloaded textures it uses. Throws as buildExportModel. With `atlases`
// (whose plant meshes went through applyLeafAtlas), a plant's leaves are one part, "leaves",
// with the material of its atlas, whose image it takes.
// With `maps` (ExportOptions::maps), bark and leaf materials get normal maps and the bark a
// roughness map (io/material_maps.h), made from their textures.
ExportModel assembleExportModel(const ExportScene& scene, const std::vector<PlantParts>& parts,
                                TexturePreload& textures, LeafAtlases* atlases = nullptr, bool maps = false);

}  // namespace tendril::io

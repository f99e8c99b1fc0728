// The step both exporters share: mesh every plant (in parallel), load each texture once and
// give every part a material. Textures and materials are shared between plants when they are
// the same (same image spec; same kind, texture and factors).
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/io/texture.h"
#include "tendril/mesh/plant_mesh.h"

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
  enum class Kind { Bark, Leaf, Plain };
  Kind kind = Kind::Plain;
  std::string name;
  Vec4 baseColor = Vec4::Ones();  // linear RGBA factor, in [0, 1]
  float roughness = 1.0f;
  float metallic = 0.0f;
  int texture = -1;                // index into ExportModel::textures
  bool alphaMask = false;          // leaves: cut out where texture alpha < 0.5
  bool doubleSided = false;
};

struct ExportPart {
  std::string name;            // "bark", "leaves-0", a primitive or mesh name
  const TriangleMesh* mesh = nullptr;  // points into ExportModel; never empty
  int material = 0;
};

struct ExportObject {
  std::string name;  // the plant's (or extra mesh's) name
  std::vector<ExportPart> parts;
};

// Parts point into the model's own meshes: move it, do not copy it.
struct ExportModel {
  ExportModel() = default;
  ExportModel(ExportModel&&) = default;
  ExportModel& operator=(ExportModel&&) = default;
  ExportModel(const ExportModel&) = delete;
  ExportModel& operator=(const ExportModel&) = delete;

  std::vector<mesh::PlantMesh> plantMeshes;  // one per scene plant
  std::vector<TriangleMesh> extraMeshes;     // scene meshes with normals ensured
  std::vector<ExportObject> objects;         // plants, then extra meshes
  std::vector<ExportMaterial> materials;
  std::vector<ExportTexture> textures;
  std::vector<ExportImage> images;
};

// Throws Error for invalid plants or options and for textures that cannot be read.
ExportModel buildExportModel(const ExportScene& scene, const ExportOptions& options);

}  // namespace tendril::io

// Scene files (JSON, documented in docs/scene-format.md): the environment (obstacles from
// primitives and mesh files, lights, strokes, wind), the plants and how to write them out.
// Reading is strict: any unknown key, wrong type or out-of-range value is an Error naming the
// file and the JSON pointer; a missing or broken mesh names its path.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/env/environment.h"
#include "tendril/models/plant_spec.h"
#include "tendril/wind/sph.h"

#include <filesystem>
#include <string>
#include <vector>

namespace tendril::scene {

inline constexpr int kSceneFormatVersion = 1;

struct OutputSettings {
  int radialSegments = 8;       // around each branch
  int subdivisions = 3;         // spline samples per segment
  bool includeObstacles = false;  // write the obstacles into the exported files too
  // A looping wind animation (Growth-Flow motion) written next to the plant; 0 s = none.
  float animationSeconds = 0.0f;
  int animationFps = 24;
  int animationJoints = 128;      // joints per plant's skin
  // Levels of detail per plant (mesh/lod.h): LOD0 included (1 = none); LODk's triangle budget
  // is LOD0's triangles × lodRatio^k, or lodTriangles[k − 1] when given (lods − 1 of them).
  int lods = 1;
  float lodRatio = 0.45f;
  std::vector<uint64_t> lodTriangles;
  // Engine wind data in the .glb's vertex attributes (docs/engine-wind.md).
  bool windData = false;
  // All of a plant's leaf textures packed into one atlas, its leaves one material (io/leaf_atlas.h).
  bool leafAtlas = false;
  // A slab billboard impostor as each plant's last level of detail (io/impostor.h):
  // `"impostor": true` or an object with "slabs" and "resolution".
  bool impostor = false;
  int impostorSlabs = 8;
  int impostorResolution = 256;
  // A graph plant's repeated primitive shapes written once each and drawn by GPU instancing
  // (EXT_mesh_gpu_instancing) in the .glb where that makes it smaller (io/instancing.h).
  bool instancing = false;
  // Bark normal and roughness maps and leaf normal maps made with their textures (io/material_maps.h).
  bool maps = false;
  // Pivot Painter 2-style textures beside the .glb, per plant, and their UVs in it (io/pivot_painter.h).
  bool pivotPainter = false;
};

struct Scene {
  std::string description;  // free text for people (optional)
  std::filesystem::path path;  // the file it came from ("" for built-in/in-memory scenes)
  std::string source;          // how errors name it: the path, or what parseScene was told
  uint64_t seed = 1;
  int steps = 300;            // growth steps run by `tendril grow`
  float stepTime = 1.0f;      // plant age per growth step (s)
  std::vector<env::ObstacleDef> obstacles;
  std::vector<env::Light> lights;
  std::vector<env::Stroke> strokes;
  env::WindSettings wind;
  // wind.mode == sph: the simulated air (seed 000 §5.3) and whether it starts filled with air
  // moving at wind.velocity (else only the emitters bring air).
  wind::SphSettings sph;
  bool sphFill = true;
  std::vector<models::PlantSpec> plants;
  OutputSettings output;
};

// Reads and checks a scene file (meshes are loaded here, so their errors surface now).
Scene loadScene(const std::filesystem::path& path);
// Parses scene JSON; `source` names it in errors, `baseDir` resolves relative paths.
Scene parseScene(const Json& json, const std::string& source, const std::filesystem::path& baseDir);

// Parses one plant object of a scene (the "plants" entries); `pointer` is its JSON pointer and
// `index` its place (default name "plant<index>", default seed index + 1).
models::PlantSpec parsePlant(const Json& plant, const std::string& source, const std::string& pointer,
                     const std::filesystem::path& baseDir, size_t index);

// Fills an environment with the scene's obstacles, lights, strokes and wind, and commits it.
void populateEnvironment(const Scene& scene, env::Environment& env);

}  // namespace tendril::scene

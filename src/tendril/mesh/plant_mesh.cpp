#include "tendril/mesh/plant_mesh.h"

#include "tendril/core/error.h"

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include <cmath>

namespace tendril::mesh {

size_t PlantMesh::triangleCount() const {
  size_t n = bark.triangleCount();
  for (const TriangleMesh& m : leaves) n += m.triangleCount();
  for (const PrimitiveGroup& g : primitives) n += g.mesh.triangleCount();
  return n;
}

void checkMeshable(const plant::PlantModel& plant, const MeshOptions& options) {
  std::string source = plant.name.empty() ? std::string("plant") : plant.name;
  plant::validate(plant, source);
  for (size_t s = 0; s < plant.leafShapes.size(); ++s)
    if (!(std::isfinite(plant.leafShapes[s].aspect) && plant.leafShapes[s].aspect > 0.0f))
      throw Error(source, fmt::format("leaf shape {}", s),
                  fmt::format("aspect (blade width / length) must be finite and > 0, got {}", plant.leafShapes[s].aspect));
  validateMeshOptions(options, "mesh options");
}

void buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options, PlantMesh& mesh) {
  checkMeshable(plant, options);
  tbb::parallel_invoke([&] { sweepBranches(plant, options, mesh.bark); },
                       [&] { buildLeafQuads(plant, options, mesh.leaves); },
                       [&] { mesh.primitives = buildPrimitiveMeshes(plant); });
}

PlantMesh buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options) {
  PlantMesh mesh;
  buildPlantMesh(plant, options, mesh);
  return mesh;
}

}  // namespace tendril::mesh

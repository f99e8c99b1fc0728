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

PlantMesh buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options) {
  std::string source = plant.name.empty() ? std::string("plant") : plant.name;
  plant::validate(plant, source);
  for (size_t s = 0; s < plant.leafShapes.size(); ++s)
    if (!(std::isfinite(plant.leafShapes[s].aspect) && plant.leafShapes[s].aspect > 0.0f))
      throw Error(source, fmt::format("leaf shape {}", s),
                  fmt::format("aspect (blade width / length) must be finite and > 0, got {}", plant.leafShapes[s].aspect));
  validateMeshOptions(options, "mesh options");
  PlantMesh mesh;
  tbb::parallel_invoke([&] { mesh.bark = sweepBranches(plant, options); },
                       [&] { mesh.leaves = buildLeafQuads(plant, options); },
                       [&] { mesh.primitives = buildPrimitiveMeshes(plant); });
  return mesh;
}

}  // namespace tendril::mesh

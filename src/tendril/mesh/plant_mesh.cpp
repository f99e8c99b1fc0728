#include "tendril/mesh/plant_mesh.h"

#include <tbb/parallel_invoke.h>

namespace tendril::mesh {

size_t PlantMesh::triangleCount() const {
  size_t n = bark.triangleCount();
  for (const TriangleMesh& m : leaves) n += m.triangleCount();
  for (const PrimitiveGroup& g : primitives) n += g.mesh.triangleCount();
  return n;
}

PlantMesh buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options) {
  plant::validate(plant, plant.name.empty() ? std::string("plant") : plant.name);
  validateMeshOptions(options, "mesh options");
  PlantMesh mesh;
  tbb::parallel_invoke([&] { mesh.bark = sweepBranches(plant, options); },
                       [&] { mesh.leaves = buildLeafQuads(plant, options); },
                       [&] { mesh.primitives = buildPrimitiveMeshes(plant); });
  return mesh;
}

}  // namespace tendril::mesh

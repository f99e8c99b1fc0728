// PlantModel → triangle meshes: the bark sweep, leaf quads grouped by shape and the primitive
// meshes, all in world space. The one call apps and exporters use; the pieces live in
// branch_sweep.h, leaf_mesh.h and primitive_mesh.h. Every vertex carries the skeleton node it was
// built from (TriangleMesh::nodeIds: bark, the node whose segment it was swept from; leaves, the
// node the leaf hangs on; primitives, their node), which the .glb writes as _NODE_ID and the
// wind clip skins by.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/mesh/branch_sweep.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/mesh/primitive_mesh.h"
#include "tendril/plant/plant_model.h"

#include <vector>

namespace tendril::mesh {

struct PlantMesh {
  TriangleMesh bark;                       // every branch chain of the skeleton
  std::vector<TriangleMesh> leaves;        // index = leaf shape id (leafShapeCount() entries)
  std::vector<PrimitiveGroup> primitives;  // one per material

  size_t triangleCount() const;
};

// Validates the plant (Error naming it on bad data) and the options, then meshes it. Bark and
// leaves are built in parallel; the result is bit-identical for any thread count.
PlantMesh buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options = {});
// The same into `mesh`, whose arrays keep the memory they have (a mesh reused from plant to
// plant allocates only when a plant is larger than any before it).
void buildPlantMesh(const plant::PlantModel& plant, const MeshOptions& options, PlantMesh& mesh);

// The checks buildPlantMesh makes before meshing: throws the Error it would throw.
void checkMeshable(const plant::PlantModel& plant, const MeshOptions& options);

}  // namespace tendril::mesh

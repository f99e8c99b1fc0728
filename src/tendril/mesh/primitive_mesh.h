// Primitive meshes (the graph model's Simple/Revo shapes) placed in the world:
// worldFromPrimitive = worldFromNode · nodeFromPrimitive (node −1: the identity, i.e. the
// primitive's matrix is already world-space).
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/plant/plant_model.h"

#include <string>
#include <vector>

namespace tendril::mesh {

// Primitives sharing a material (colour and texture) merged into one world-space mesh.
struct PrimitiveGroup {
  std::string name;     // name of the first PrimitiveMesh in the group
  Vec3 color = Vec3(0.8f, 0.8f, 0.8f);
  std::string texture;  // empty: untextured
  TriangleMesh mesh;    // always has unit normals; uvs when any member has them (0 elsewhere)
};

// worldFromNode of a skeleton node as a matrix (−1: identity).
Mat4 worldFromNode(const plant::PlantModel& plant, int32_t node);

// Groups in order of first use. Normals are transformed by the inverse transpose (and computed
// where a mesh has none); mirroring transforms flip the winding so faces still point out. Each
// vertex's node id (TriangleMesh::nodeIds) is its primitive's node, node 0 (the first root) for
// a primitive on node −1; a plant without nodes gives meshes without node ids.
std::vector<PrimitiveGroup> buildPrimitiveMeshes(const plant::PlantModel& plant);

}  // namespace tendril::mesh

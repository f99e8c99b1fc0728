// Leaf blades as textured quads (seed 003 §3.10: leaves are parallelograms in the plane of the
// leaf node's frame, textured with leaf images).
//
// A leaf's blade lies in its local XY plane: it starts at the attachment point moved `petiole`
// along leaf +Y, extends `size` along +Y and `size · aspect` across X, centred on the Y axis;
// its normal is leaf +Z (the upper side). UV (0, 0) is the blade's base-left corner and (1, 1)
// its tip-right corner, so the image's bottom centre is where the petiole joins (v grows with
// the image's up direction, OpenGL/OBJ convention; the glTF writer flips it).
//
// With leafSubdivisions = L the blade is L quads long and bends about leaf X by the wind
// state's bend angle leafMotion.x() (radians; positive curls the tip toward +Z): the blade's
// direction turns uniformly along its length, reaching the full angle at the tip, so it keeps
// its length. Zero motion gives a flat blade. The twist and vibration angles (y, z) are not
// drawn here.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/mesh/mesh_options.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <vector>

namespace tendril::mesh {

inline constexpr const char* kDefaultLeafTexture = "builtin:ivy-0";

// Number of leaf shape ids in use: leafShapes.size(), or more when leaves use ids beyond it.
size_t leafShapeCount(const plant::PlantModel& plant);
// The shape id `shape` stands for. Ids without a LeafShape, and shapes without a texture, are
// drawn with kDefaultLeafTexture (the id's aspect and tint are kept when it has an entry).
plant::LeafShape leafShapeFor(const plant::PlantModel& plant, size_t shape);

// Vertices and indices of one leaf for `leafSubdivisions` quads.
inline size_t leafVertexCount(const MeshOptions& o) { return 2 * (static_cast<size_t>(o.leafSubdivisions) + 1); }
inline size_t leafIndexCount(const MeshOptions& o) { return 6 * static_cast<size_t>(o.leafSubdivisions); }

// Writes leaf `leaf` into leafVertexCount() vertices and leafIndexCount() indices (indices
// start at `baseVertex`). `aspect` is its shape's width / length.
void buildLeafQuad(const plant::PlantModel& plant, size_t leaf, float aspect, const MeshOptions& options,
                   Vec3* positions, Vec3* normals, Vec2* uvs, uint32_t* indices, uint32_t baseVertex);

// Every leaf, one mesh per shape id (index = shape id; leafShapeCount() meshes, some may be
// empty), leaves in index order, each vertex's node id (TriangleMesh::nodeIds) the node its leaf
// hangs on. Parallel, bit-identical for any thread count.
std::vector<TriangleMesh> buildLeafQuads(const plant::PlantModel& plant, const MeshOptions& options);
// The same into `meshes` (resized; reused meshes keep their memory).
void buildLeafQuads(const plant::PlantModel& plant, const MeshOptions& options, std::vector<TriangleMesh>& meshes);

}  // namespace tendril::mesh

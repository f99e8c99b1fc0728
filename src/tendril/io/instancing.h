// GPU instancing of a graph plant's repeated primitives (issue 26 part 6; docs/export.md
// "GPU instancing"): the .glb may write each primitive shape (plant::PrimitiveMesh: a leaf,
// petal, seed or fruit that a component graph repeats) once, in its own frame, with one
// translation / rotation / scale per copy (EXT_mesh_gpu_instancing), instead of every copy
// baked into its primitive group's mesh.
//
// A shape is instanced where that makes the file smaller: its instance data (40 bytes of
// transform per copy, plus the node id and, with engine wind data, 40 bytes of wind) and its
// one mesh and JSON cost less than its baked copies' vertices and indices. A copy whose
// transform is not a rotation times a per-axis scale (sheared, or mirrored: glTF instancing
// has no winding flip) is baked, whatever its shape. Only LOD0's primitives are candidates:
// lower levels of detail have each primitive group simplified as a whole by meshoptimizer
// (mesh/lod.h), so their copies are no longer alike and stay baked.
//
// Deterministic, independent of the thread count.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/mesh/primitive_mesh.h"
#include "tendril/plant/plant_model.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tendril::io {

// One primitive shape drawn at many places.
struct InstancedShape {
  uint32_t group = 0;  // the primitive group (mesh::PrimitiveGroup, its material) it belongs to
  uint32_t mesh = 0;   // index into plant::PlantModel::meshes
  std::string name;    // the mesh's name
  // In the primitive's own frame: unit normals, uvs when its group has any (0 where the shape
  // has none, as in the baked group), no node ids (each copy has one, below).
  TriangleMesh shape;
  std::vector<Vec3> translation;  // per copy
  std::vector<Vec4> rotation;     // unit quaternion (x, y, z, w), w >= 0
  std::vector<Vec3> scale;        // per axis, > 0
  std::vector<uint32_t> nodeIds;  // the node it hangs on (as the baked vertices' node ids); empty for a plant without nodes

  size_t instances() const { return translation.size(); }
  // Translation · Rotation · Scale of copy i (the order EXT_mesh_gpu_instancing composes them).
  Mat4 transform(size_t i) const;
};

struct PlantInstancing {
  std::vector<InstancedShape> shapes;  // by group, then by mesh index
  // Per primitive group with instances: its primitives that are not, baked as
  // mesh::buildPrimitiveMeshes bakes them (empty when every one is an instance, and for a group
  // without instances, which is written from its own mesh).
  std::vector<TriangleMesh> rest;
  // Per primitive group: 0 none of its primitives is an instance, 1 some are, 2 all are.
  std::vector<uint8_t> instanced;
  bool empty() const { return shapes.empty(); }
};

// What decides whether a shape is worth instancing.
struct InstancingCost {
  bool wind = false;        // engine wind data: 40 more bytes per baked vertex, and per copy
  bool cacheOrder = false;  // a LOD chain: the rest and the shapes in vertex cache and fetch order
};

// The plant's primitives instanced where that makes the .glb smaller. `groups` are the plant's
// LOD0 primitive groups (mesh::buildPrimitiveMeshes; their meshes give the baked sizes). An
// empty result (no shape worth it) leaves the plant as it is.
PlantInstancing instancePrimitives(const plant::PlantModel& plant, const std::vector<mesh::PrimitiveGroup>& groups,
                                   const InstancingCost& cost);

// Splits an affine transform into translation, rotation (quaternion x, y, z, w with w >= 0) and
// per-axis scale when it is one (columns orthogonal, positive determinant; relative tolerance
// 1e-4); false otherwise.
bool decomposeTrs(const Mat4& m, Vec3& translation, Vec4& rotation, Vec3& scale);

}  // namespace tendril::io

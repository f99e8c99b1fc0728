// An indexed triangle mesh: the geometry type shared by obstacles (env), generated plant
// geometry (mesh), export (io) and rendering. Counter-clockwise winding seen from the side the
// normal points to.
#pragma once

#include "tendril/core/math.h"

#include <cstdint>
#include <vector>

namespace tendril {

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // empty, or one unit normal per position
  std::vector<Vec2> uvs;      // empty, or one per position
  std::vector<uint32_t> indices;
  // Empty, or one per position: the plant skeleton node the vertex was built from (plant
  // meshes, mesh/plant_mesh.h; the .glb's _NODE_ID).
  std::vector<uint32_t> nodeIds;

  size_t vertexCount() const { return positions.size(); }
  size_t triangleCount() const { return indices.size() / 3; }
  bool empty() const { return indices.empty(); }
  void clear() {
    positions.clear();
    normals.clear();
    uvs.clear();
    indices.clear();
    nodeIds.clear();
  }
  Bounds3 bounds() const {
    Bounds3 b;
    for (const Vec3& p : positions) b.extend(p);
    return b;
  }
  // Appends `other` (whose attributes must be present exactly when ours are, or ours empty).
  void append(const TriangleMesh& other);
  // Applies an affine transform to positions and its inverse-transpose to normals.
  void transform(const Eigen::Affine3f& t);
  // Replaces normals by area-weighted vertex normals.
  void computeNormals();
};

}  // namespace tendril

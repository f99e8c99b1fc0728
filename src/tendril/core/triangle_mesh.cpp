#include "tendril/core/triangle_mesh.h"

namespace tendril {

void TriangleMesh::append(const TriangleMesh& o) {
  // An attribute survives only if both meshes have it (or this one was empty).
  bool wasEmpty = positions.empty();
  bool keepNormals = !o.normals.empty() && (wasEmpty || !normals.empty());
  bool keepUvs = !o.uvs.empty() && (wasEmpty || !uvs.empty());
  bool keepNodeIds = !o.nodeIds.empty() && (wasEmpty || !nodeIds.empty());
  uint32_t base = static_cast<uint32_t>(positions.size());
  positions.insert(positions.end(), o.positions.begin(), o.positions.end());
  if (keepNormals)
    normals.insert(normals.end(), o.normals.begin(), o.normals.end());
  else
    normals.clear();
  if (keepUvs)
    uvs.insert(uvs.end(), o.uvs.begin(), o.uvs.end());
  else
    uvs.clear();
  if (keepNodeIds)
    nodeIds.insert(nodeIds.end(), o.nodeIds.begin(), o.nodeIds.end());
  else
    nodeIds.clear();
  indices.reserve(indices.size() + o.indices.size());
  for (uint32_t i : o.indices) indices.push_back(base + i);
}

void TriangleMesh::transform(const Eigen::Affine3f& t) {
  for (Vec3& p : positions) p = t * p;
  if (!normals.empty()) {
    Mat3 n = t.linear().inverse().transpose();
    for (Vec3& v : normals) v = (n * v).normalized();
  }
}

void TriangleMesh::computeNormals() {
  normals.assign(positions.size(), Vec3::Zero());
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const Vec3& a = positions[indices[t]];
    const Vec3& b = positions[indices[t + 1]];
    const Vec3& c = positions[indices[t + 2]];
    Vec3 n = (b - a).cross(c - a);  // length = 2 * area: area weighting for free
    for (int k = 0; k < 3; ++k) normals[indices[t + k]] += n;
  }
  for (Vec3& n : normals) {
    float len = n.norm();
    n = len > 0.0f ? Vec3(n / len) : Vec3::UnitY();
  }
}

}  // namespace tendril

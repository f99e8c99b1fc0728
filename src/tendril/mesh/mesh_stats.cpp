#include "tendril/mesh/mesh_stats.h"

#include <cmath>

namespace tendril::mesh {

MeshStats analyzeMesh(const TriangleMesh& m) {
  MeshStats s;
  s.vertices = m.positions.size();
  s.triangles = m.indices.size() / 3;
  s.invalidIndices = m.indices.size() % 3;
  s.attributesMatch = (m.normals.empty() || m.normals.size() == s.vertices) &&
                      (m.uvs.empty() || m.uvs.size() == s.vertices);
  for (size_t i = 0; i < s.vertices; ++i) {
    bool finite = isFinite(m.positions[i]);
    if (i < m.normals.size()) {
      finite = finite && isFinite(m.normals[i]);
      if (!(std::abs(m.normals[i].norm() - 1.0f) <= 1e-3f)) ++s.nonUnitNormals;
    }
    if (i < m.uvs.size()) finite = finite && isFinite(m.uvs[i]);
    if (!finite) ++s.nonFinite;
    s.bounds.extend(m.positions[i]);
  }
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    if (a >= s.vertices || b >= s.vertices || c >= s.vertices) {
      ++s.invalidIndices;
      continue;
    }
    Vec3 n = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
    if (a == b || b == c || a == c || !(0.5f * n.norm() >= 1e-12f)) ++s.degenerateTriangles;
  }
  return s;
}

}  // namespace tendril::mesh

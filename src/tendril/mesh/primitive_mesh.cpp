#include "tendril/mesh/primitive_mesh.h"

#include <algorithm>
#include <cmath>

namespace tendril::mesh {

using plant::PlantModel;

Mat4 worldFromNode(const PlantModel& plant, int32_t node) {
  Mat4 m = Mat4::Identity();
  if (node < 0) return m;
  m.topLeftCorner<3, 3>() = plant.orientation[node].toRotationMatrix();
  m.topRightCorner<3, 1>() = plant.position[node];
  return m;
}

std::vector<PrimitiveGroup> buildPrimitiveMeshes(const PlantModel& plant) {
  std::vector<PrimitiveGroup> groups;
  // Which group each primitive joins, and whether that group carries uvs.
  std::vector<size_t> groupOf(plant.primitives.size());
  std::vector<uint8_t> hasUvs;
  for (size_t i = 0; i < plant.primitives.size(); ++i) {
    const plant::PrimitiveMesh& pm = plant.meshes[plant.primitives[i].mesh];
    auto it = std::find_if(groups.begin(), groups.end(), [&](const PrimitiveGroup& g) {
      return g.color == pm.color && g.texture == pm.texture;
    });
    if (it == groups.end()) {
      groups.push_back({pm.name, pm.color, pm.texture, {}});
      hasUvs.push_back(0);
      it = groups.end() - 1;
    }
    size_t g = static_cast<size_t>(it - groups.begin());
    groupOf[i] = g;
    if (!pm.mesh.uvs.empty()) hasUvs[g] = 1;
  }
  for (size_t i = 0; i < plant.primitives.size(); ++i) {
    const plant::Primitive& pr = plant.primitives[i];
    const TriangleMesh& src = plant.meshes[pr.mesh].mesh;
    if (src.empty()) continue;
    TriangleMesh part = src;
    Eigen::Affine3f t(worldFromNode(plant, pr.node) * pr.nodeFromPrimitive);
    if (t.linear().determinant() < 0.0f)
      for (size_t k = 0; k + 2 < part.indices.size(); k += 3) std::swap(part.indices[k + 1], part.indices[k + 2]);
    part.transform(t);
    // Missing or unusable normals (zero, or collapsed by a singular transform) are recomputed.
    bool unitNormals = !part.normals.empty() && std::all_of(part.normals.begin(), part.normals.end(), [](const Vec3& n) {
      return std::abs(n.squaredNorm() - 1.0f) < 1e-3f;
    });
    if (!unitNormals) part.computeNormals();
    size_t g = groupOf[i];
    if (hasUvs[g] && part.uvs.empty()) part.uvs.assign(part.positions.size(), Vec2::Zero());
    part.nodeIds.clear();
    if (plant.nodeCount() > 0) part.nodeIds.assign(part.positions.size(), uint32_t(std::max(pr.node, 0)));
    groups[g].mesh.append(part);
  }
  return groups;
}

}  // namespace tendril::mesh

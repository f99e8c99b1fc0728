#include "tendril/io/instancing.h"

#include "tendril/mesh/lod.h"

#include <algorithm>
#include <cmath>

namespace tendril::io {
namespace {

// Bytes the .glb spends on one shape's node, mesh, primitive and its accessors and views (JSON),
// about; wind data adds three instance accessors.
constexpr size_t kJsonPerShape = 1600, kJsonWind = 600;

bool unitNormals(const TriangleMesh& m) {
  return !m.normals.empty() && std::all_of(m.normals.begin(), m.normals.end(), [](const Vec3& n) {
    return std::abs(n.squaredNorm() - 1.0f) < 1e-3f;
  });
}

// The group a primitive mesh joins: groups are told apart by colour and texture
// (mesh::buildPrimitiveMeshes).
int groupOf(const std::vector<mesh::PrimitiveGroup>& groups, const plant::PrimitiveMesh& pm) {
  for (size_t g = 0; g < groups.size(); ++g)
    if (groups[g].color == pm.color && groups[g].texture == pm.texture) return int(g);
  return -1;
}

// One primitive baked into `out` as mesh::buildPrimitiveMeshes bakes it.
void bake(const plant::PlantModel& plant, const plant::Primitive& pr, bool uvs, TriangleMesh& out) {
  const TriangleMesh& src = plant.meshes[pr.mesh].mesh;
  if (src.empty()) return;
  TriangleMesh part = src;
  Eigen::Affine3f t(mesh::worldFromNode(plant, pr.node) * pr.nodeFromPrimitive);
  if (t.linear().determinant() < 0.0f)
    for (size_t k = 0; k + 2 < part.indices.size(); k += 3) std::swap(part.indices[k + 1], part.indices[k + 2]);
  part.transform(t);
  if (!unitNormals(part)) part.computeNormals();
  if (uvs && part.uvs.empty()) part.uvs.assign(part.positions.size(), Vec2::Zero());
  part.nodeIds.clear();
  if (plant.nodeCount() > 0) part.nodeIds.assign(part.positions.size(), uint32_t(std::max(pr.node, 0)));
  out.append(part);
}

}  // namespace

Mat4 InstancedShape::transform(size_t i) const {
  const Vec4& r = rotation[i];
  Mat4 m = Mat4::Identity();
  m.topLeftCorner<3, 3>() = Quat(r.w(), r.x(), r.y(), r.z()).toRotationMatrix() * scale[i].asDiagonal();
  m.topRightCorner<3, 1>() = translation[i];
  return m;
}

bool decomposeTrs(const Mat4& m, Vec3& translation, Vec4& rotation, Vec3& scale) {
  if (!m.allFinite()) return false;
  const Mat3 l = m.topLeftCorner<3, 3>();
  Mat3 r;
  for (int c = 0; c < 3; ++c) {
    scale[c] = l.col(c).norm();
    if (!(scale[c] > 1e-12f)) return false;
    r.col(c) = l.col(c) / scale[c];
  }
  // Orthonormal columns (no shear) and no mirroring.
  if (!((r.transpose() * r - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-4f) || r.determinant() < 0.0f) return false;
  Quat q(r);
  q.normalize();
  if (q.w() < 0.0f) q.coeffs() = -q.coeffs();
  rotation = Vec4(q.x(), q.y(), q.z(), q.w());
  translation = m.topRightCorner<3, 1>();
  return true;
}

PlantInstancing instancePrimitives(const plant::PlantModel& plant, const std::vector<mesh::PrimitiveGroup>& groups,
                                   const InstancingCost& cost) {
  PlantInstancing out;
  const size_t meshes = plant.meshes.size();
  // Per mesh: its group and the primitives whose transform instancing can carry.
  std::vector<int> group(meshes, -1);
  for (size_t m = 0; m < meshes; ++m) group[m] = groupOf(groups, plant.meshes[m]);
  std::vector<std::vector<uint32_t>> copies(meshes);
  std::vector<Mat4> world(plant.primitives.size());
  for (size_t i = 0; i < plant.primitives.size(); ++i) {
    const plant::Primitive& pr = plant.primitives[i];
    if (pr.mesh >= meshes || group[pr.mesh] < 0 || plant.meshes[pr.mesh].mesh.empty()) continue;
    world[i] = mesh::worldFromNode(plant, pr.node) * pr.nodeFromPrimitive;
    Vec3 t, s;
    Vec4 r;
    if (decomposeTrs(world[i], t, r, s)) copies[pr.mesh].push_back(uint32_t(i));
  }
  // Which shapes are worth it, by their bytes in the file either way.
  const bool nodes = plant.nodeCount() > 0;
  std::vector<uint8_t> instanced(meshes, 0);
  for (size_t m = 0; m < meshes; ++m) {
    if (copies[m].empty()) continue;
    const TriangleMesh& shape = plant.meshes[m].mesh;
    const mesh::PrimitiveGroup& g = groups[size_t(group[m])];
    const bool uvs = !g.mesh.uvs.empty();
    const size_t v = shape.vertexCount(), i = shape.indices.size();
    const size_t bakedVertex = 24 + (uvs ? 8 : 0) + (nodes ? 4 : 0) + (nodes && cost.wind ? 40 : 0);
    const size_t bakedIndex = g.mesh.vertexCount() < 65536 ? 2 : 4;
    const size_t baked = copies[m].size() * (v * bakedVertex + i * bakedIndex);
    const size_t perCopy = 40 + (nodes ? 4 : 0) + (nodes && cost.wind ? 40 : 0);
    const size_t inst = v * (24 + (uvs ? 8 : 0)) + i * (v < 65536 ? 2 : 4) + copies[m].size() * perCopy +
                        kJsonPerShape + (cost.wind ? kJsonWind : 0);
    instanced[m] = inst < baked ? 1 : 0;
  }
  if (std::none_of(instanced.begin(), instanced.end(), [](uint8_t x) { return x != 0; })) return out;

  // The shapes, by group then mesh index.
  for (size_t g = 0; g < groups.size(); ++g)
    for (size_t m = 0; m < meshes; ++m) {
      if (!instanced[m] || group[m] != int(g)) continue;
      InstancedShape s;
      s.group = uint32_t(g);
      s.mesh = uint32_t(m);
      s.name = plant.meshes[m].name;
      s.shape = plant.meshes[m].mesh;
      s.shape.nodeIds.clear();
      if (!unitNormals(s.shape)) s.shape.computeNormals();
      if (!groups[g].mesh.uvs.empty() && s.shape.uvs.empty()) s.shape.uvs.assign(s.shape.vertexCount(), Vec2::Zero());
      if (groups[g].mesh.uvs.empty()) s.shape.uvs.clear();
      if (cost.cacheOrder) mesh::optimizeMeshOrder(s.shape);
      for (uint32_t i : copies[m]) {
        Vec3 t, sc;
        Vec4 r;
        decomposeTrs(world[i], t, r, sc);
        s.translation.push_back(t);
        s.rotation.push_back(r);
        s.scale.push_back(sc);
        if (nodes) s.nodeIds.push_back(uint32_t(std::max(plant.primitives[i].node, 0)));
      }
      out.shapes.push_back(std::move(s));
    }

  // What stays baked: every primitive of a shape not instanced, and the copies of an instanced
  // one that instancing cannot carry.
  std::vector<uint8_t> isCopy(plant.primitives.size(), 0);
  for (size_t m = 0; m < meshes; ++m)
    if (instanced[m])
      for (uint32_t i : copies[m]) isCopy[i] = 1;
  out.rest.resize(groups.size());
  out.instanced.assign(groups.size(), 0);
  std::vector<uint8_t> some(groups.size(), 0);
  for (const InstancedShape& s : out.shapes) some[s.group] = 1;
  for (size_t i = 0; i < plant.primitives.size(); ++i) {
    const plant::Primitive& pr = plant.primitives[i];
    if (isCopy[i] || pr.mesh >= meshes || group[pr.mesh] < 0) continue;
    const size_t g = size_t(group[pr.mesh]);
    if (!some[g]) continue;  // written from the group's own mesh
    bake(plant, pr, !groups[g].mesh.uvs.empty(), out.rest[g]);
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    if (cost.cacheOrder) mesh::optimizeMeshOrder(out.rest[g]);
    out.instanced[g] = !some[g] ? 0 : out.rest[g].empty() ? 2 : 1;
  }
  return out;
}

}  // namespace tendril::io

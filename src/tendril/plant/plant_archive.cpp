#include "tendril/plant/plant_archive.h"

#include "tendril/core/json_reader.h"

#include <fmt/format.h>

#include <cmath>

namespace tendril::plant {

namespace {

constexpr uint32_t kPlantTag = 0x4d4c5031;  // "1PLM"

void saveMesh(ArchiveWriter& out, const TriangleMesh& m) {
  out.vector(m.positions);
  out.vector(m.normals);
  out.vector(m.uvs);
  out.vector(m.indices);
}

void loadMesh(ArchiveReader& in, TriangleMesh& m) {
  in.vector(m.positions);
  in.vector(m.normals);
  in.vector(m.uvs);
  in.vector(m.indices);
  for (uint32_t i : m.indices)
    if (i >= m.positions.size()) in.fail("a primitive mesh index lies outside its vertices");
}

}  // namespace

void savePlantModel(ArchiveWriter& out, const PlantModel& p) {
  out.tag(kPlantTag);
  out.string(p.name);
  out.string(p.species);
  out.string(p.bark.texture);
  out.value(p.bark.color);
  out.f32(p.bark.roughness);
  out.u64(p.leafShapes.size());
  for (const LeafShape& s : p.leafShapes) {
    out.string(s.texture);
    out.f32(s.aspect);
    out.value(s.tint);
  }
  out.vector(p.position), out.vector(p.orientation), out.vector(p.length), out.vector(p.radius);
  out.vector(p.parent), out.vector(p.age), out.vector(p.order), out.vector(p.flags);
  out.vector(p.leafNode), out.vector(p.leafOffset), out.vector(p.leafRotation), out.vector(p.leafSize);
  out.vector(p.leafThickness), out.vector(p.leafPetiole), out.vector(p.leafShape), out.vector(p.leafMotion);
  out.u64(p.meshes.size());
  for (const PrimitiveMesh& m : p.meshes) {
    out.string(m.name);
    saveMesh(out, m.mesh);
    out.value(m.color);
    out.string(m.texture);
  }
  out.vector(p.primitives);
}

void loadPlantModel(ArchiveReader& in, PlantModel& p) {
  in.tag(kPlantTag, "a plant");
  p.name = in.string();
  p.species = in.string();
  p.bark.texture = in.string();
  in.value(p.bark.color);
  p.bark.roughness = in.f32();
  p.leafShapes.resize(size_t(in.count(16, "leaf shapes")));
  for (LeafShape& s : p.leafShapes) {
    s.texture = in.string();
    s.aspect = in.f32();
    in.value(s.tint);
  }
  in.vector(p.position), in.vector(p.orientation), in.vector(p.length), in.vector(p.radius);
  in.vector(p.parent), in.vector(p.age), in.vector(p.order), in.vector(p.flags);
  in.vector(p.leafNode), in.vector(p.leafOffset), in.vector(p.leafRotation), in.vector(p.leafSize);
  in.vector(p.leafThickness), in.vector(p.leafPetiole), in.vector(p.leafShape), in.vector(p.leafMotion);
  p.meshes.resize(size_t(in.count(40, "primitive meshes")));
  for (PrimitiveMesh& m : p.meshes) {
    m.name = in.string();
    loadMesh(in, m.mesh);
    in.value(m.color);
    m.texture = in.string();
  }
  in.vector(p.primitives);

  const size_t n = p.position.size(), l = p.leafNode.size();
  if (p.orientation.size() != n || p.length.size() != n || p.radius.size() != n || p.parent.size() != n ||
      p.age.size() != n || p.order.size() != n || p.flags.size() != n)
    in.fail("the node arrays of a saved plant differ in length");
  if (p.leafOffset.size() != l || p.leafRotation.size() != l || p.leafSize.size() != l ||
      p.leafThickness.size() != l || p.leafPetiole.size() != l || p.leafShape.size() != l ||
      (!p.leafMotion.empty() && p.leafMotion.size() != l))
    in.fail("the leaf arrays of a saved plant differ in length");
  for (size_t i = 0; i < n; ++i)
    if (p.parent[i] < -1 || p.parent[i] >= int32_t(i))
      in.fail(fmt::format("node {} of a saved plant has parent {}", i, p.parent[i]));
  for (int32_t node : p.leafNode)
    if (node < 0 || size_t(node) >= n) in.fail(fmt::format("a leaf of a saved plant hangs from node {}", node));
  for (const Primitive& pr : p.primitives)
    if (pr.node < -1 || pr.node >= int32_t(n) || pr.mesh >= p.meshes.size())
      in.fail("a primitive of a saved plant refers to a missing node or mesh");
  // Values the models turn into cell indices or sweep into meshes: finite, within the world
  // (100 km of the origin), rotations of unit length.
  constexpr float kFar = float(JsonObject::kWorldExtent);  // the readers' world
  auto near = [](const Vec3& v) { return isFinite(v) && v.cwiseAbs().maxCoeff() <= kFar; };
  auto unit = [](const Quat& q) { return std::isfinite(q.squaredNorm()) && std::abs(q.squaredNorm() - 1.0f) < 1e-2f; };
  auto size = [](float v) { return v >= 0.0f && v <= kFar; };
  for (size_t i = 0; i < n; ++i)
    if (!near(p.position[i]) || !unit(p.orientation[i]) || !size(p.length[i]) || !size(p.radius[i]) ||
        !std::isfinite(p.age[i]))
      in.fail(fmt::format("node {} of a saved plant holds a value out of range", i));
  for (size_t i = 0; i < l; ++i)
    if (!near(p.leafOffset[i]) || !unit(p.leafRotation[i]) || !size(p.leafSize[i]) || !size(p.leafThickness[i]) ||
        !size(p.leafPetiole[i]) || (!p.leafMotion.empty() && !isFinite(p.leafMotion[i])))
      in.fail(fmt::format("leaf {} of a saved plant holds a value out of range", i));
}

}  // namespace tendril::plant

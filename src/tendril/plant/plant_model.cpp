#include "tendril/plant/plant_model.h"

#include "tendril/core/error.h"
#include "tendril/core/hash.h"

#include <fmt/format.h>

#include <cmath>

namespace tendril::plant {

int32_t PlantModel::addNode(const NodeDef& d) {
  position.push_back(d.position);
  orientation.push_back(d.orientation);
  length.push_back(d.length);
  radius.push_back(d.radius);
  parent.push_back(d.parent);
  age.push_back(d.age);
  order.push_back(d.order);
  flags.push_back(d.flags);
  return static_cast<int32_t>(position.size() - 1);
}

int32_t PlantModel::addLeaf(const LeafDef& d) {
  leafNode.push_back(d.node);
  leafOffset.push_back(d.offset);
  leafRotation.push_back(d.rotation);
  leafSize.push_back(d.size);
  leafThickness.push_back(d.thickness);
  leafPetiole.push_back(d.petiole);
  leafShape.push_back(d.shape);
  leafMotion.push_back(Vec3::Zero());
  return static_cast<int32_t>(leafNode.size() - 1);
}

void PlantModel::keepLeaves(const std::vector<uint32_t>& kept) {
  const size_t count = leafCount();
  if (kept.size() == count) return;  // ascending and all of them: every leaf stays
  // Ascending indices: leaf kept[o] moves down to o, never over one still to be read.
  auto pick = [&](auto& v) {
    for (size_t o = 0; o < kept.size(); ++o) v[o] = v[kept[o]];
    v.resize(kept.size());
  };
  pick(leafNode), pick(leafOffset), pick(leafRotation), pick(leafSize);
  pick(leafThickness), pick(leafPetiole), pick(leafShape);
  if (leafMotion.size() == count) pick(leafMotion);
}

void PlantModel::reserve(size_t nodes, size_t leaves) {
  position.reserve(nodes);
  orientation.reserve(nodes);
  length.reserve(nodes);
  radius.reserve(nodes);
  parent.reserve(nodes);
  age.reserve(nodes);
  order.reserve(nodes);
  flags.reserve(nodes);
  leafNode.reserve(leaves);
  leafOffset.reserve(leaves);
  leafRotation.reserve(leaves);
  leafSize.reserve(leaves);
  leafThickness.reserve(leaves);
  leafPetiole.reserve(leaves);
  leafShape.reserve(leaves);
  leafMotion.reserve(leaves);
}

void PlantModel::clear() {
  PlantModel empty;
  empty.name = name;
  empty.species = species;
  empty.bark = bark;
  empty.leafShapes = leafShapes;
  *this = std::move(empty);
}

void PlantModel::children(std::vector<int32_t>& childStart, std::vector<int32_t>& childIndex) const {
  size_t n = nodeCount();
  childStart.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i)
    if (parent[i] >= 0) ++childStart[parent[i] + 1];
  for (size_t i = 0; i < n; ++i) childStart[i + 1] += childStart[i];
  childIndex.assign(childStart[n], 0);
  std::vector<int32_t> fill(childStart.begin(), childStart.end() - 1);
  for (size_t i = 0; i < n; ++i)
    if (parent[i] >= 0) childIndex[fill[parent[i]]++] = static_cast<int32_t>(i);
}

void validate(const PlantModel& p, const std::string& source) {
  size_t n = p.position.size();
  auto sizeError = [&](const char* what) {
    return Error(source, "", fmt::format("plant \"{}\": array {} has a different size", p.name, what));
  };
  if (p.orientation.size() != n) throw sizeError("orientation");
  if (p.length.size() != n) throw sizeError("length");
  if (p.radius.size() != n) throw sizeError("radius");
  if (p.parent.size() != n) throw sizeError("parent");
  if (p.age.size() != n) throw sizeError("age");
  if (p.order.size() != n) throw sizeError("order");
  if (p.flags.size() != n) throw sizeError("flags");
  for (size_t i = 0; i < n; ++i) {
    auto bad = [&](const std::string& what) {
      return Error(source, fmt::format("node {}", i), fmt::format("plant \"{}\": {}", p.name, what));
    };
    if (!isFinite(p.position[i])) throw bad("position is not finite");
    if (!isFinite(p.orientation[i])) throw bad("orientation is not finite");
    if (std::abs(p.orientation[i].squaredNorm() - 1.0f) > 1e-3f) throw bad("orientation is not a unit quaternion");
    if (!std::isfinite(p.length[i]) || p.length[i] < 0.0f) throw bad("length must be finite and >= 0");
    if (!std::isfinite(p.radius[i]) || p.radius[i] <= 0.0f) throw bad("radius must be finite and > 0");
    if (!std::isfinite(p.age[i])) throw bad("age is not finite");
    if (p.parent[i] < -1 || p.parent[i] >= static_cast<int32_t>(i))
      throw bad(fmt::format("parent {} does not come before the node", p.parent[i]));
  }
  size_t m = p.leafNode.size();
  auto leafSizeError = [&](const char* what) {
    return Error(source, "", fmt::format("plant \"{}\": leaf array {} has a different size", p.name, what));
  };
  if (p.leafOffset.size() != m) throw leafSizeError("offset");
  if (p.leafRotation.size() != m) throw leafSizeError("rotation");
  if (p.leafSize.size() != m) throw leafSizeError("size");
  if (p.leafThickness.size() != m) throw leafSizeError("thickness");
  if (p.leafPetiole.size() != m) throw leafSizeError("petiole");
  if (p.leafShape.size() != m) throw leafSizeError("shape");
  if (p.leafMotion.size() != m) throw leafSizeError("motion");
  for (size_t i = 0; i < m; ++i) {
    auto bad = [&](const std::string& what) {
      return Error(source, fmt::format("leaf {}", i), fmt::format("plant \"{}\": {}", p.name, what));
    };
    if (p.leafNode[i] < 0 || p.leafNode[i] >= static_cast<int32_t>(n)) throw bad("is attached to a missing node");
    if (!isFinite(p.leafOffset[i]) || !isFinite(p.leafRotation[i]) || !isFinite(p.leafMotion[i]))
      throw bad("frame is not finite");
    if (std::abs(p.leafRotation[i].squaredNorm() - 1.0f) > 1e-3f) throw bad("rotation is not a unit quaternion");
    if (!std::isfinite(p.leafSize[i]) || p.leafSize[i] <= 0.0f) throw bad("size must be finite and > 0");
    if (!std::isfinite(p.leafThickness[i]) || p.leafThickness[i] < 0.0f) throw bad("thickness must be >= 0");
    if (!std::isfinite(p.leafPetiole[i]) || p.leafPetiole[i] < 0.0f) throw bad("petiole must be >= 0");
    if (!p.leafShapes.empty() && p.leafShape[i] >= p.leafShapes.size()) throw bad("shape id has no LeafShape");
  }
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    const Primitive& pr = p.primitives[i];
    auto bad = [&](const std::string& what) {
      return Error(source, fmt::format("primitive {}", i), fmt::format("plant \"{}\": {}", p.name, what));
    };
    if (pr.node < -1 || pr.node >= static_cast<int32_t>(n)) throw bad("is attached to a missing node");
    if (pr.mesh >= p.meshes.size()) throw bad("refers to a missing mesh");
    if (!pr.nodeFromPrimitive.allFinite()) throw bad("transform is not finite");
  }
  for (size_t i = 0; i < p.meshes.size(); ++i) {
    const TriangleMesh& mesh = p.meshes[i].mesh;
    auto bad = [&](const std::string& what) {
      return Error(source, fmt::format("mesh {}", i), fmt::format("plant \"{}\": {}", p.name, what));
    };
    if (mesh.indices.size() % 3 != 0) throw bad("index count is not a multiple of 3");
    for (uint32_t idx : mesh.indices)
      if (idx >= mesh.positions.size()) throw bad("index out of range");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size()) throw bad("normal count differs");
    if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size()) throw bad("uv count differs");
    for (const Vec3& v : mesh.positions)
      if (!isFinite(v)) throw bad("position is not finite");
  }
}

PlantStats computeStats(const PlantModel& p) {
  PlantStats s;
  s.nodes = p.nodeCount();
  s.leaves = p.leafCount();
  std::vector<uint8_t> hasChild(s.nodes, 0);
  for (size_t i = 0; i < s.nodes; ++i) {
    if (p.parent[i] < 0) ++s.roots;
    else hasChild[p.parent[i]] = 1;
    if (p.parent[i] < 0 || (p.flags[i] & kNodeBranchStart)) ++s.branches;
    s.maxOrder = std::max(s.maxOrder, p.order[i]);
    s.totalLength += p.length[i];
    s.bounds.extend(p.position[i]);
    s.bounds.extend(p.tip(i));
  }
  for (size_t i = 0; i < s.nodes; ++i)
    if (!hasChild[i]) ++s.tips;
  for (size_t i = 0; i < s.leaves; ++i) s.bounds.extend(p.leafWorldPosition(i));
  return s;
}

uint64_t contentHash(const PlantModel& p) {
  Hasher h;
  h.add(std::string_view(p.name));
  h.add(std::string_view(p.species));
  h.add(std::string_view(p.bark.texture));
  h.add(p.bark.color);
  h.add(p.bark.roughness);
  h.add(uint64_t(p.leafShapes.size()));
  for (const LeafShape& s : p.leafShapes) {
    h.add(std::string_view(s.texture));
    h.add(s.aspect);
    h.add(s.tint);
  }
  h.add(p.position);
  h.add(p.orientation);
  h.add(p.length);
  h.add(p.radius);
  h.add(p.parent);
  h.add(p.age);
  h.add(p.order);
  h.add(p.flags);
  h.add(p.leafNode);
  h.add(p.leafOffset);
  h.add(p.leafRotation);
  h.add(p.leafSize);
  h.add(p.leafThickness);
  h.add(p.leafPetiole);
  h.add(p.leafShape);
  h.add(p.leafMotion);
  h.add(uint64_t(p.meshes.size()));
  for (const PrimitiveMesh& m : p.meshes) {
    h.add(std::string_view(m.name));
    h.add(m.mesh.positions);
    h.add(m.mesh.normals);
    h.add(m.mesh.uvs);
    h.add(m.mesh.indices);
    h.add(m.color);
    h.add(std::string_view(m.texture));
  }
  h.add(uint64_t(p.primitives.size()));
  for (const Primitive& pr : p.primitives) {
    h.add(pr.node);
    h.add(pr.mesh);
    h.add(pr.nodeFromPrimitive);
  }
  return h.digest();
}

uint64_t contentHash(const std::vector<PlantModel>& plants) {
  Hasher h;
  for (const PlantModel& p : plants) h.add(contentHash(p));
  return h.digest();
}

}  // namespace tendril::plant

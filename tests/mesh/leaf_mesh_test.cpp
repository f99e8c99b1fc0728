#include "tendril/mesh/leaf_mesh.h"

#include "support/determinism.h"
#include "support/synthetic_plants.h"
#include "tendril/core/hash.h"
#include "tendril/mesh/mesh_stats.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tendril::mesh {
namespace {

using plant::PlantModel;

// One node at (1, 2, 3) turned about X, one leaf on it with a known frame.
PlantModel oneLeaf(float aspect, float bend = 0.0f) {
  PlantModel p = meshtest::straightChain(1, 0.2f, 0.01f, 0.01f, Vec3(1, 2, 3));
  p.orientation[0] = axisAngle(Vec3(1, 0.5f, 0), 0.4f);
  plant::LeafShape shape;
  shape.texture = "builtin:heart-0";
  shape.aspect = aspect;
  p.leafShapes.push_back(shape);
  PlantModel::LeafDef l;
  l.node = 0;
  l.offset = Vec3(0, 0.1f, 0.01f);
  l.rotation = axisAngle(Vec3(0.2f, 0.3f, 1.0f), 1.1f);
  l.size = 0.08f;
  l.petiole = 0.03f;
  p.addLeaf(l);
  p.leafMotion[0].x() = bend;
  return p;
}

TEST(MeshLeaves, QuadCornersAreWhereTheLeafFrameSays) {
  PlantModel p = oneLeaf(0.75f);
  std::vector<TriangleMesh> leaves = buildLeafQuads(p, MeshOptions{});
  ASSERT_EQ(leaves.size(), 1u);
  const TriangleMesh& m = leaves[0];
  ASSERT_EQ(m.vertexCount(), 4u);
  ASSERT_EQ(m.triangleCount(), 2u);
  Quat q = p.orientation[0] * p.leafRotation[0];
  Vec3 x = q * Vec3::UnitX(), y = q * Vec3::UnitY(), z = q * Vec3::UnitZ();
  Vec3 base = p.position[0] + p.orientation[0] * p.leafOffset[0] + 0.03f * y;
  float halfWidth = 0.5f * 0.08f * 0.75f;
  // (uv, expected position) for base-left, base-right, tip-left, tip-right.
  std::vector<std::pair<Vec2, Vec3>> corners = {
      {Vec2(0, 0), base - halfWidth * x},
      {Vec2(1, 0), base + halfWidth * x},
      {Vec2(0, 1), base + 0.08f * y - halfWidth * x},
      {Vec2(1, 1), base + 0.08f * y + halfWidth * x},
  };
  for (const auto& [uv, pos] : corners) {
    bool found = false;
    for (size_t i = 0; i < 4; ++i) {
      if (m.uvs[i] != uv) continue;
      found = true;
      EXPECT_LT((m.positions[i] - pos).norm(), 2e-6f) << uv.transpose();
      EXPECT_LT((m.normals[i] - z).norm(), 1e-6f);
    }
    EXPECT_TRUE(found) << uv.transpose();
  }
  // Both triangles face the leaf's +Z (counter-clockwise seen from the upper side).
  for (size_t t = 0; t < 2; ++t) {
    const Vec3& a = m.positions[m.indices[3 * t]];
    const Vec3& b = m.positions[m.indices[3 * t + 1]];
    const Vec3& c = m.positions[m.indices[3 * t + 2]];
    EXPECT_GT((b - a).cross(c - a).dot(z), 0.0f);
  }
}

TEST(MeshLeaves, SubdividedBladeIsFlatWithoutMotionAndBendsWithIt) {
  MeshOptions o;
  o.leafSubdivisions = 6;
  {
    PlantModel p = oneLeaf(1.0f);
    TriangleMesh m = buildLeafQuads(p, o)[0];
    ASSERT_EQ(m.vertexCount(), 14u);
    ASSERT_EQ(m.triangleCount(), 12u);
    Vec3 z = p.leafWorldRotation(0) * Vec3::UnitZ();
    for (const Vec3& v : m.positions) EXPECT_NEAR((v - m.positions[0]).dot(z), 0.0f, 1e-6f);
    EXPECT_LT((m.positions[13] - m.positions[1] - 0.08f * (p.leafWorldRotation(0) * Vec3::UnitY())).norm(), 3e-6f);
  }
  {
    float bend = 0.6f;
    PlantModel p = oneLeaf(1.0f, bend);
    TriangleMesh m = buildLeafQuads(p, o)[0];
    Quat q = p.leafWorldRotation(0);
    Vec3 y = q * Vec3::UnitY(), z = q * Vec3::UnitZ();
    // The blade keeps its length along the midline and its tip normal turned by the bend.
    float length = 0.0f;
    for (int k = 0; k < 6; ++k) length += (m.positions[2 * k + 2] - m.positions[2 * k]).norm();
    EXPECT_NEAR(length, 0.08f, 1e-5f);
    EXPECT_NEAR(m.normals[12].dot(z), std::cos(bend), 1e-5f);
    EXPECT_NEAR(m.normals[12].dot(-y), std::sin(bend), 1e-5f);
    // Positive bend curls the tip toward the upper side.
    EXPECT_GT((m.positions[12] - m.positions[0]).dot(z), 0.01f);
    EXPECT_EQ(analyzeMesh(m).nonUnitNormals, 0u);
  }
}

TEST(MeshLeaves, GroupedByShape) {
  PlantModel p = meshtest::branchingTree();
  meshtest::addLeaves(p, 3);
  std::vector<TriangleMesh> leaves = buildLeafQuads(p, MeshOptions{});
  ASSERT_EQ(leaves.size(), 3u);
  size_t counts[3] = {0, 0, 0};
  for (uint16_t s : p.leafShape) ++counts[s];
  for (size_t s = 0; s < 3; ++s) {
    EXPECT_EQ(leaves[s].vertexCount(), 4 * counts[s]);
    EXPECT_EQ(leaves[s].triangleCount(), 2 * counts[s]);
    MeshStats st = analyzeMesh(leaves[s]);
    EXPECT_EQ(st.nonUnitNormals, 0u);
    EXPECT_EQ(st.degenerateTriangles, 0u);
    EXPECT_EQ(st.invalidIndices, 0u);
  }
  // A shape id without a LeafShape entry still gets a mesh, drawn with the default texture.
  p.leafShape[0] = 5;
  p.leafShapes.clear();
  leaves = buildLeafQuads(p, MeshOptions{});
  EXPECT_EQ(leaves.size(), 6u);
  EXPECT_EQ(leaves[5].vertexCount(), 4u);
  EXPECT_EQ(leafShapeFor(p, 5).texture, kDefaultLeafTexture);
}

TEST(MeshLeaves, OutputIsIndependentOfThreadCount) {
  PlantModel p = meshtest::syntheticIvy(8000);
  for (size_t i = 0; i < p.leafCount(); ++i) p.leafMotion[i].x() = 0.001f * float(i % 300);
  MeshOptions o;
  o.leafSubdivisions = 3;
  auto hash = [&] {
    Hasher h;
    for (const TriangleMesh& m : buildLeafQuads(p, o)) {
      h.add(m.positions);
      h.add(m.normals);
      h.add(m.uvs);
      h.add(m.indices);
    }
    return h.digest();
  };
  tendril::test::sameAtEveryThreadCount(hash);
}

}  // namespace
}  // namespace tendril::mesh

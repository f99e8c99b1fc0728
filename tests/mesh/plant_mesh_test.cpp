#include "tendril/mesh/plant_mesh.h"

#include "support/determinism.h"
#include "support/synthetic_plants.h"
#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/mesh/mesh_stats.h"

#include <gtest/gtest.h>

namespace tendril::mesh {
namespace {

using plant::PlantModel;

TriangleMesh unitTriangle(bool withNormals) {
  TriangleMesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  if (withNormals) m.normals.assign(3, Vec3::UnitZ());
  m.indices = {0, 1, 2};
  return m;
}

void addPrimitive(PlantModel& p, int32_t node, uint32_t mesh, const Mat4& t) {
  plant::Primitive pr;
  pr.node = node;
  pr.mesh = mesh;
  pr.nodeFromPrimitive = t;
  p.primitives.push_back(pr);
}

TEST(MeshPrimitives, PlacedByNodeAndPrimitiveTransforms) {
  PlantModel p = meshtest::straightChain(3);
  p.orientation[1] = axisAngle(Vec3::UnitY(), 0.5f * kPi);  // node +X → world −Z
  p.meshes.push_back({"leaf-disc", unitTriangle(true), Vec3(0.2f, 0.6f, 0.2f), ""});
  p.meshes.push_back({"flower", unitTriangle(false), Vec3(0.9f, 0.1f, 0.1f), ""});
  Mat4 shift = Mat4::Identity();
  shift.topRightCorner<3, 1>() = Vec3(0.5f, 0, 0);
  addPrimitive(p, 1, 0, shift);
  addPrimitive(p, -1, 1, Mat4::Identity());
  addPrimitive(p, 2, 0, Mat4::Identity());  // same material as the first: same group
  std::vector<PrimitiveGroup> groups = buildPrimitiveMeshes(p);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].name, "leaf-disc");
  EXPECT_EQ(groups[0].mesh.vertexCount(), 6u);
  EXPECT_EQ(groups[1].mesh.vertexCount(), 3u);
  // worldFromNode · nodeFromPrimitive applied to vertex (1, 0, 0): node 1 at (0, 0.1, 0).
  Vec3 expected = p.position[1] + p.orientation[1] * Vec3(1.5f, 0, 0);
  EXPECT_LT((groups[0].mesh.positions[1] - expected).norm(), 1e-6f);
  EXPECT_LT((groups[0].mesh.normals[0] - p.orientation[1] * Vec3::UnitZ()).norm(), 1e-6f);
  // The mesh without normals gets computed ones; node −1 is the identity.
  EXPECT_EQ(groups[1].mesh.positions[1], Vec3(1, 0, 0));
  EXPECT_LT((groups[1].mesh.normals[0] - Vec3::UnitZ()).norm(), 1e-6f);
}

TEST(MeshPrimitives, MirroringKeepsFacesOutward) {
  PlantModel p = meshtest::straightChain(1);
  p.meshes.push_back({"m", unitTriangle(true), Vec3::Ones(), ""});
  Mat4 mirror = Mat4::Identity();
  mirror(2, 2) = -1.0f;  // z → −z: the normal flips, so must the winding
  addPrimitive(p, -1, 0, mirror);
  TriangleMesh m = buildPrimitiveMeshes(p)[0].mesh;
  Vec3 face = (m.positions[m.indices[1]] - m.positions[m.indices[0]])
                  .cross(m.positions[m.indices[2]] - m.positions[m.indices[0]]);
  EXPECT_GT(face.dot(m.normals[0]), 0.0f);
  EXPECT_LT((m.normals[0] + Vec3::UnitZ()).norm(), 1e-6f);
}

TEST(MeshPlant, BuildsEveryPart) {
  PlantModel p = meshtest::branchingTree();
  meshtest::addLeaves(p, 2);
  p.meshes.push_back({"bud", unitTriangle(true), Vec3(1, 0, 0), ""});
  addPrimitive(p, 5, 0, Mat4::Identity());
  PlantMesh m = buildPlantMesh(p);
  EXPECT_GT(m.bark.triangleCount(), 0u);
  ASSERT_EQ(m.leaves.size(), 2u);
  EXPECT_EQ(m.leaves[0].triangleCount() + m.leaves[1].triangleCount(), 2 * p.leafCount());
  ASSERT_EQ(m.primitives.size(), 1u);
  EXPECT_EQ(m.triangleCount(),
            m.bark.triangleCount() + 2 * p.leafCount() + m.primitives[0].mesh.triangleCount());
  for (const TriangleMesh* t : {&m.bark, &m.leaves[0], &m.leaves[1], &m.primitives[0].mesh}) {
    MeshStats s = analyzeMesh(*t);
    EXPECT_EQ(s.nonFinite, 0u);
    EXPECT_EQ(s.nonUnitNormals, 0u);
    EXPECT_EQ(s.invalidIndices, 0u);
  }
  // The bark covers the skeleton.
  plant::PlantStats stats = plant::computeStats(p);
  Bounds3 b = analyzeMesh(m.bark).bounds;
  EXPECT_LE(b.min.y(), stats.bounds.min.y() + 1e-5f);
  EXPECT_GE(b.max.y(), stats.bounds.max.y() - 0.05f);
}

TEST(MeshPlant, RejectsBadPlantsAndOptions) {
  PlantModel p = meshtest::straightChain(3);
  p.radius[1] = -1.0f;
  EXPECT_THROW(buildPlantMesh(p), Error);
  MeshOptions o;
  o.radialSegments = 2;
  try {
    buildPlantMesh(meshtest::straightChain(3), o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "radialSegments");
  }
  o = MeshOptions{};
  o.subdivisions = 0;
  EXPECT_THROW(buildPlantMesh(meshtest::straightChain(3), o), Error);
  PlantModel flat = meshtest::straightChain(3);
  meshtest::addLeaves(flat, 2);
  flat.leafShapes[1].aspect = 0.0f;
  try {
    buildPlantMesh(flat);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "leaf shape 1");
  }
}

TEST(MeshPlant, EmptyPlantGivesEmptyMeshes) {
  PlantMesh m = buildPlantMesh(PlantModel{});
  EXPECT_TRUE(m.bark.empty());
  EXPECT_TRUE(m.leaves.empty());
  EXPECT_TRUE(m.primitives.empty());
  EXPECT_EQ(m.triangleCount(), 0u);
}

TEST(MeshPlant, OutputIsIndependentOfThreadCount) {
  PlantModel p = meshtest::syntheticIvy(5000);
  auto hash = [&] {
    PlantMesh m = buildPlantMesh(p);
    Hasher h;
    for (const TriangleMesh* t : {&m.bark, &m.leaves[0], &m.leaves[1], &m.leaves[2]}) {
      h.add(t->positions);
      h.add(t->normals);
      h.add(t->uvs);
      h.add(t->indices);
    }
    return h.digest();
  };
  tendril::test::sameAtEveryThreadCount(hash);
}

}  // namespace
}  // namespace tendril::mesh

#include "tendril/env/primitives.h"
#include "tendril/env/topology.h"

#include <gtest/gtest.h>

namespace tendril::env {
namespace {

void expectClosed(const TriangleMesh& m, double volume, double tolerance) {
  TopologyReport r = analyzeTopology(weld(m));
  EXPECT_EQ(r.boundaryEdges, 0u);
  EXPECT_EQ(r.nonManifoldEdges, 0u);
  EXPECT_EQ(r.inconsistentEdges, 0u);
  EXPECT_EQ(r.degenerateTriangles, 0u);
  EXPECT_TRUE(r.closed());
  EXPECT_NEAR(r.signedVolume, volume, tolerance);  // positive = outward winding
}

TEST(Primitives, BoxIsClosedAndOutward) { expectClosed(makeBox(Vec3(1, 2, 3)), 6.0, 1e-5); }

TEST(Primitives, PlaneIsASlabBelowZero) {
  TriangleMesh m = makePlane(Vec2(4, 6), 0.1f);
  expectClosed(m, 2.4, 1e-5);
  EXPECT_NEAR(m.bounds().max.y(), 0.0f, 1e-6f);
  EXPECT_NEAR(m.bounds().min.y(), -0.1f, 1e-6f);
}

TEST(Primitives, SphereVolumeConverges) {
  double exact = 4.0 / 3.0 * M_PI;
  expectClosed(makeSphere(1.0f, 4), exact, 0.01 * exact);
}

TEST(Primitives, CylinderIsClosedAndOutward) {
  double exact = M_PI * 0.25 * 2.0;
  expectClosed(makeCylinder(0.5f, 2.0f, 64), exact, 0.01 * exact);
}

TEST(Primitives, WallWithOpeningsIsClosedManifold) {
  std::vector<WallOpening> openings = {{Vec2(-0.8f, 1.5f), Vec2(0.6f, 0.8f)}, {Vec2(0.9f, 1.0f), Vec2(0.5f, 1.2f)}};
  ASSERT_EQ(checkWallOpenings(Vec3(4, 3, 0.2f), openings), "");
  TriangleMesh m = makeWall(Vec3(4, 3, 0.2f), openings);
  double volume = 0.2 * (4 * 3 - 0.6 * 0.8 - 0.5 * 1.2);
  expectClosed(m, volume, 1e-4);
  EXPECT_NEAR(m.bounds().min.y(), 0.0f, 1e-6f);
}

TEST(Primitives, WallOpeningChecks) {
  Vec3 size(4, 3, 0.2f);
  EXPECT_NE(checkWallOpenings(size, {{Vec2(1.9f, 1.5f), Vec2(0.5f, 0.5f)}}), "");  // crosses the side
  EXPECT_NE(checkWallOpenings(size, {{Vec2(0, 1), Vec2(1, 1)}, {Vec2(0.5f, 1.2f), Vec2(1, 1)}}), "");
  EXPECT_NE(checkWallOpenings(size, {{Vec2(0, 1), Vec2(0, 1)}}), "");
  EXPECT_EQ(checkWallOpenings(size, {{Vec2(0, 1), Vec2(1, 1)}, {Vec2(1.2f, 1), Vec2(0.5f, 1)}}), "");
}

TEST(Topology, OpenMeshIsReported) {
  TriangleMesh m = makeBox(Vec3(1, 1, 1));
  m.indices.resize(m.indices.size() - 6);  // remove one face
  TopologyReport r = analyzeTopology(weld(m));
  EXPECT_EQ(r.boundaryEdges, 4u);
  EXPECT_FALSE(r.closed());
}

TEST(Topology, ClosestPointOnTriangleFeatures) {
  Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  auto f = closestPointOnTriangle(Vec3(0.2f, 0.2f, 1), a, b, c);
  EXPECT_EQ(f.feature, TriangleFeature::Face);
  EXPECT_TRUE(f.point.isApprox(Vec3(0.2f, 0.2f, 0)));
  auto e = closestPointOnTriangle(Vec3(0.5f, -1, 0), a, b, c);
  EXPECT_EQ(e.feature, TriangleFeature::EdgeAB);
  EXPECT_TRUE(e.point.isApprox(Vec3(0.5f, 0, 0)));
  auto v = closestPointOnTriangle(Vec3(-1, -1, 0), a, b, c);
  EXPECT_EQ(v.feature, TriangleFeature::VertexA);
  auto h = closestPointOnTriangle(Vec3(1, 1, 0), a, b, c);
  EXPECT_EQ(h.feature, TriangleFeature::EdgeBC);
  EXPECT_TRUE(h.point.isApprox(Vec3(0.5f, 0.5f, 0)));
}

}  // namespace
}  // namespace tendril::env

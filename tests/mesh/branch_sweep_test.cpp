#include "tendril/mesh/branch_sweep.h"

#include "support/determinism.h"
#include "support/synthetic_plants.h"
#include "tendril/core/hash.h"
#include "tendril/mesh/mesh_stats.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tendril::mesh {
namespace {

using meshtest::arcChain;
using meshtest::branchingTree;
using meshtest::straightChain;
using plant::PlantModel;

// Centre of ring `ring` of a chain whose rings start at vertex `first`: the mean of its
// vertices (the seam duplicate left out) — exact for a circle of evenly spaced vertices.
Vec3 ringCentre(const TriangleMesh& m, size_t first, size_t ring, int radial) {
  Vec3 c = Vec3::Zero();
  for (int j = 0; j < radial; ++j) c += m.positions[first + ring * (radial + 1) + j];
  return c / float(radial);
}

void expectClean(const TriangleMesh& m) {
  MeshStats s = analyzeMesh(m);
  EXPECT_EQ(s.nonFinite, 0u);
  EXPECT_EQ(s.nonUnitNormals, 0u);
  EXPECT_EQ(s.invalidIndices, 0u);
  EXPECT_TRUE(s.attributesMatch);
}

TEST(MeshChains, BranchStartsAndExtraChildrenStartChains) {
  PlantModel p = branchingTree();
  BranchChains chains = buildBranchChains(p);
  ASSERT_EQ(chains.size(), 4u);
  auto list = [&](size_t c) { return std::vector<int32_t>(chains.chain(c).begin(), chains.chain(c).end()); };
  EXPECT_EQ(list(0), (std::vector<int32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(list(1), (std::vector<int32_t>{6, 7, 8}));
  EXPECT_EQ(list(2), (std::vector<int32_t>{9, 10}));
  EXPECT_EQ(list(3), (std::vector<int32_t>{11}));
  // Several roots: one chain each.
  PlantModel two = straightChain(3);
  PlantModel::NodeDef d;
  d.position = Vec3(1, 0, 0);
  d.length = 0.1f;
  d.radius = 0.01f;
  two.addNode(d);
  EXPECT_EQ(buildBranchChains(two).size(), 2u);
}

TEST(MeshSweep, VertexAndIndexCountsFollowTheLayout) {
  PlantModel p = branchingTree();
  for (bool caps : {true, false}) {
    MeshOptions o;
    o.radialSegments = 7;
    o.subdivisions = 4;
    o.caps = caps;
    TriangleMesh m = sweepBranches(p, o);
    BranchChains chains = buildBranchChains(p);
    size_t ring = o.radialSegments + 1;
    size_t vertices = 0, triangles = 0;
    for (size_t c = 0; c < chains.size(); ++c) {
      size_t samples = chains.chain(c).size() * o.subdivisions + 1;  // segments · subdivisions + tip
      vertices += samples * ring + (caps ? 2 * ring : 0);
      triangles += (samples - 1) * 2 * o.radialSegments + (caps ? 2 * o.radialSegments : 0);
    }
    EXPECT_EQ(m.vertexCount(), vertices);
    EXPECT_EQ(m.triangleCount(), triangles);
    expectClean(m);
    EXPECT_EQ(analyzeMesh(m).degenerateTriangles, 0u);
  }
}

TEST(MeshSweep, RingsSitOnTheSkeletonAtTheNodeRadius) {
  PlantModel p = straightChain(5, 0.1f, 0.02f, 0.01f);
  MeshOptions o;
  o.caps = false;
  TriangleMesh m = sweepBranches(p, o);
  int radial = o.radialSegments;
  size_t rings = 5 * o.subdivisions + 1;
  ASSERT_EQ(m.vertexCount(), rings * (radial + 1));
  for (size_t r = 0; r < rings; ++r) {
    // Along a straight stem the spline is the stem itself, and the radius is interpolated
    // linearly from each node's radius to the next one's (the tip keeps the last radius).
    size_t segment = std::min<size_t>(r / o.subdivisions, 4);
    float s = float(r - segment * o.subdivisions) / float(o.subdivisions);
    float r0 = p.radius[segment], r1 = segment + 1 < 5 ? p.radius[segment + 1] : p.radius[4];
    float radius = r0 + (r1 - r0) * s;
    for (int j = 0; j <= radial; ++j) {
      const Vec3& v = m.positions[r * (radial + 1) + j];
      EXPECT_NEAR(std::hypot(v.x(), v.z()), radius, 1e-6f);
      EXPECT_NEAR(v.y(), 0.1f * float(r) / float(o.subdivisions), 1e-5f);
    }
  }
  // Ring centres at node boundaries are the node positions.
  for (int n = 0; n < 5; ++n)
    EXPECT_LT((ringCentre(m, 0, n * o.subdivisions, radial) - p.position[n]).norm(), 1e-6f);
}

TEST(MeshSweep, CurvedChainRingsKeepTheirRadiusAndPassThroughNodes) {
  PlantModel p = arcChain(12, 0.5f, 2.5f, 0.015f);
  MeshOptions o;
  o.caps = false;
  o.subdivisions = 5;
  TriangleMesh m = sweepBranches(p, o);
  int radial = o.radialSegments;
  size_t rings = 12 * o.subdivisions + 1;
  ASSERT_EQ(m.vertexCount(), rings * (radial + 1));
  for (size_t r = 0; r < rings; ++r) {
    Vec3 c = ringCentre(m, 0, r, radial);
    for (int j = 0; j <= radial; ++j) EXPECT_NEAR((m.positions[r * (radial + 1) + j] - c).norm(), 0.015f, 2e-6f);
    // The spline of an arc stays close to the arc (radius 0.5 about (0.5, 0)).
    EXPECT_NEAR((c - Vec3(0.5f, 0, 0)).norm(), 0.5f, 2e-3f);
  }
  for (int n = 0; n < 12; ++n) EXPECT_LT((ringCentre(m, 0, n * o.subdivisions, radial) - p.position[n]).norm(), 1e-5f);
  EXPECT_LT((ringCentre(m, 0, rings - 1, radial) - p.tip(11)).norm(), 1e-5f);
}

TEST(MeshSweep, FramesDoNotTwistAlongAPlanarBranch) {
  // The arc lies in the XY plane and its nodes' +Z is the plane normal: the first ring vertex
  // (the frame normal direction) must stay on the +Z side all along, without twisting.
  PlantModel p = arcChain(20, 0.4f, 3.0f, 0.01f);
  MeshOptions o;
  o.caps = false;
  TriangleMesh m = sweepBranches(p, o);
  int radial = o.radialSegments;
  size_t rings = m.vertexCount() / (radial + 1);
  for (size_t r = 0; r < rings; ++r) {
    Vec3 c = ringCentre(m, 0, r, radial);
    Vec3 seam = (m.positions[r * (radial + 1)] - c) / 0.01f;
    EXPECT_GT(seam.z(), 0.9999f) << "ring " << r;
  }
}

TEST(MeshSweep, UvsAreContinuousAlongTheChain) {
  PlantModel p = arcChain(10, 0.3f, 2.0f, 0.01f);
  p.radius = {0.02f, 0.019f, 0.018f, 0.017f, 0.016f, 0.015f, 0.014f, 0.013f, 0.012f, 0.011f};
  MeshOptions o;
  o.caps = false;
  TriangleMesh m = sweepBranches(p, o);
  int radial = o.radialSegments;
  size_t rings = m.vertexCount() / (radial + 1);
  float previous = -1.0f;
  for (size_t r = 0; r < rings; ++r) {
    const Vec2* uv = &m.uvs[r * (radial + 1)];
    for (int j = 0; j <= radial; ++j) {
      EXPECT_FLOAT_EQ(uv[j].x(), float(j) / float(radial));
      EXPECT_EQ(uv[j].y(), uv[0].y());
    }
    EXPECT_GT(uv[0].y(), previous);
    if (r > 0) {
      // v = arc length / (2π · base radius): the step matches the distance between ring centres.
      float step = (ringCentre(m, 0, r, radial) - ringCentre(m, 0, r - 1, radial)).norm();
      EXPECT_NEAR(uv[0].y() - previous, step / (kTwoPi * 0.02f), 1e-4f);
    }
    previous = uv[0].y();
  }
  // The seam vertex repeats the first one's position and normal.
  for (size_t r = 0; r < rings; ++r) {
    EXPECT_EQ(m.positions[r * (radial + 1)], m.positions[r * (radial + 1) + radial]);
    EXPECT_EQ(m.normals[r * (radial + 1)], m.normals[r * (radial + 1) + radial]);
  }
}

TEST(MeshSweep, FacesPointOutward) {
  PlantModel p = arcChain(6);
  TriangleMesh m = sweepBranches(p, MeshOptions{});
  // Every triangle's geometric normal agrees with its vertices' normals (outward, caps too).
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
    Vec3 n = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
    EXPECT_GT(n.dot(m.normals[a] + m.normals[b] + m.normals[c]), 0.0f) << "triangle " << t;
  }
}

TEST(MeshSweep, TaperingBranchNormalsTiltTowardTheTip) {
  PlantModel p = straightChain(2, 0.1f, 0.05f, 0.01f);  // radius 0.05 → 0.01 over the first segment
  MeshOptions o;
  o.caps = false;
  TriangleMesh m = sweepBranches(p, o);
  // A cone narrowing upward: normals lean up (+Y).
  EXPECT_GT(m.normals[0].y(), 0.1f);
  expectClean(m);
}

TEST(MeshSweep, DegenerateInputGivesNoNaN) {
  MeshOptions o;
  // A zero-length segment and a duplicate point in the middle of a chain.
  PlantModel p = straightChain(6);
  p.length[2] = 0.0f;
  for (size_t i = 3; i < 6; ++i) p.position[i] = p.position[2] + Vec3(0, 0.1f * float(i - 3), 0);
  p.position[4] = p.position[3];
  TriangleMesh m = sweepBranches(p, o);
  expectClean(m);
  EXPECT_GT(m.triangleCount(), 0u);
  // One node.
  TriangleMesh one = sweepBranches(straightChain(1), o);
  expectClean(one);
  EXPECT_EQ(one.vertexCount(), size_t(o.subdivisions + 1) * 9 + 18);
  // One node of zero length: nothing to sweep.
  PlantModel zero = straightChain(1);
  zero.length[0] = 0.0f;
  TriangleMesh none = sweepBranches(zero, o);
  EXPECT_EQ(none.vertexCount(), 0u);
  EXPECT_EQ(none.triangleCount(), 0u);
  // A tiny radius and a segment reversing direction.
  PlantModel tiny = straightChain(3, 0.1f, 1e-9f, 1e-9f);
  tiny.orientation[1] = axisAngle(Vec3::UnitZ(), kPi);
  tiny.position[2] = tiny.tip(1);
  expectClean(sweepBranches(tiny, o));
  // Empty plant.
  EXPECT_EQ(sweepBranches(PlantModel{}, o).vertexCount(), 0u);
}

TEST(MeshSweep, PolylineOptionAndRadialSegments) {
  PlantModel p = straightChain(4);
  MeshOptions o;
  o.subdivisions = 1;
  o.radialSegments = 3;
  o.caps = false;
  TriangleMesh m = sweepBranches(p, o);
  EXPECT_EQ(m.vertexCount(), 5u * 4u);
  EXPECT_EQ(m.triangleCount(), 4u * 3u * 2u);
}

TEST(MeshSweep, OutputIsIndependentOfThreadCount) {
  PlantModel p = meshtest::syntheticIvy(6000);
  auto hash = [&] {
    TriangleMesh m = sweepBranches(p, MeshOptions{});
    Hasher h;
    h.add(m.positions);
    h.add(m.normals);
    h.add(m.uvs);
    h.add(m.indices);
    return h.digest();
  };
  tendril::test::sameAtEveryThreadCount(hash);
}

}  // namespace
}  // namespace tendril::mesh

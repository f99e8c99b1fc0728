// The geometry of Simple, Revo, Horn, Leaf, Hydra and Wreath (seed 004 sidebar): clean meshes
// facing outward, and multipliers placing their children where the parameters say.
#include "graph_test_util.h"

#include "tendril/graph/shapes.h"
#include "tendril/mesh/mesh_stats.h"

#include <cmath>

namespace tendril {
namespace {

using graphtest::instancesOf;
using graphtest::parse;

void expectClean(const TriangleMesh& m, const std::string& what) {
  mesh::MeshStats s = mesh::analyzeMesh(m);
  EXPECT_GT(s.triangles, 0u) << what;
  EXPECT_EQ(s.degenerateTriangles, 0u) << what;
  EXPECT_EQ(s.invalidIndices, 0u) << what;
  EXPECT_EQ(s.nonFinite, 0u) << what;
  EXPECT_EQ(s.nonUnitNormals, 0u) << what;
  EXPECT_TRUE(s.attributesMatch) << what;
  EXPECT_EQ(m.uvs.size(), m.positions.size()) << what;
}

// Signed volume of a closed mesh: positive when its faces point outward.
double signedVolume(const TriangleMesh& m) {
  double v = 0.0;
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
    v += double(m.positions[m.indices[t]].dot(m.positions[m.indices[t + 1]].cross(m.positions[m.indices[t + 2]]))) / 6.0;
  return v;
}

TEST(GraphShapes, SolidsAreClosedAndFaceOutward) {
  Vec3 size(0.4f, 1.0f, 0.6f);
  const double pi = M_PI;
  struct Case {
    graph::Shape shape;
    double volume;  // exact, or of the inscribed polygonal solid for round shapes
    double tolerance;
  } cases[] = {{graph::Shape::Cube, 0.4 * 1.0 * 0.6, 1e-5},
               {graph::Shape::Sphere, 4.0 / 3.0 * pi * 0.2 * 0.5 * 0.3, 0.03},
               {graph::Shape::Cylinder, pi * 0.2 * 0.3 * 1.0, 0.02},
               {graph::Shape::Cone, pi * 0.2 * 0.3 * 1.0 / 3.0, 0.02}};
  for (const Case& c : cases) {
    TriangleMesh m = graph::solidMesh(c.shape, size, 48);
    expectClean(m, graph::shapeName(c.shape));
    EXPECT_NEAR(signedVolume(m) / c.volume, 1.0, c.tolerance) << graph::shapeName(c.shape);
    Bounds3 b = m.bounds();
    EXPECT_NEAR(b.min.y(), 0.0f, 1e-6f);
    EXPECT_NEAR(b.max.y(), 1.0f, 1e-6f);
    EXPECT_NEAR(b.max.x(), 0.2f, 1e-6f);
  }
  TriangleMesh disc = graph::solidMesh(graph::Shape::Disc, size, 24);
  expectClean(disc, "disc");
  EXPECT_NEAR(signedVolume(disc), 0.0, 1e-9);  // two-sided
  EXPECT_TRUE(graph::solidMesh(graph::Shape::Cube, Vec3(0.0f, 1.0f, 1.0f), 8).empty());
}

TEST(GraphShapes, RevoHornSectionAndBladeMeshesAreClean) {
  graph::RevoParams vase;
  vase.profile = {{0.0f, 0.0f}, {0.1f, 0.0f}, {0.15f, 0.1f}, {0.08f, 0.3f}, {0.1f, 0.35f}};
  TriangleMesh revo = graph::revoMesh(vase, 6, 32);
  expectClean(revo, "revo");
  EXPECT_NEAR(revo.bounds().max.y(), 0.35f, 1e-5f);

  // A star-shaped section swept along three rings turning about X.
  std::vector<graph::Ring> rings;
  for (int k = 0; k < 3; ++k)
    rings.push_back({graph::Frame{Quat(Eigen::AngleAxisf(0.3f * float(k), Vec3::UnitX())), Vec3(0, 0.2f * float(k), 0), 1.0f},
                     0.05f});
  std::vector<Vec2> star;
  for (int k = 0; k < 10; ++k) {
    float a = kTwoPi * float(k) / 10.0f, r = k % 2 ? 0.5f : 1.0f;
    star.push_back(Vec2(r * std::cos(a), -r * std::sin(a)));
  }
  TriangleMesh horn = graph::sectionSweepMesh(rings, star);
  expectClean(horn, "horn section");
  EXPECT_GT(signedVolume(horn), 0.0);
  std::reverse(star.begin(), star.end());  // either orientation of the section faces outward
  EXPECT_GT(signedVolume(graph::sectionSweepMesh(rings, star)), 0.0);

  graph::BladeSpec blade;
  blade.aspect = 0.4f;
  blade.curvature = 0.8f;
  blade.fold = 0.5f;
  blade.outline = {{0.0f, 0.02f}, {0.4f, 0.2f}, {1.0f, 0.0f}};
  TriangleMesh b = graph::bladeMesh(blade);
  expectClean(b, "blade");
  // The bent midrib keeps its length: the tip lies on the arc of radius 1/curvature.
  float k = blade.curvature;
  Vec3 tip(0.0f, std::sin(k) / k, (std::cos(k) - 1.0f) / k);
  float nearest = 1e9f;
  for (const Vec3& p : b.positions) nearest = std::min(nearest, (p - tip).norm());
  EXPECT_LT(nearest, 1e-3f);
}

TEST(GraphShapes, HydraAndWreathPlaceTheirChildren) {
  auto g = parse(R"j({"tendril_graph": 1, "root": {"links": ["star", "ring", "arc"]}, "components": [
    {"name": "star", "type": "hydra", "params": {"count": 6, "angle": 50, "radius": 0.1, "offset": 10},
     "links": ["a"]},
    {"name": "ring", "type": "wreath", "params": {"count": 8, "radius": 0.5, "tilt": 20}, "links": ["b"]},
    {"name": "arc", "type": "wreath", "params": {"count": 5, "radius": 1, "open": 30, "close": 150}, "links": ["c"]},
    {"name": "a", "type": "simple"}, {"name": "b", "type": "simple"}, {"name": "c", "type": "simple"}]})j");
  graph::ITree t = graph::expand(g);
  auto azimuth = [](const Vec3& v) { return degrees(std::atan2(-v.x(), -v.z())); };
  std::vector<const graph::Instance*> a = instancesOf(t, "a"), b = instancesOf(t, "b"), c = instancesOf(t, "c");
  ASSERT_EQ(a.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    Vec3 dir = a[size_t(i)]->frame.rotation * Vec3::UnitY();
    EXPECT_NEAR(degrees(angleBetween(dir, Vec3::UnitY())), 50.0f, 1e-3f);
    EXPECT_NEAR(std::remainder(azimuth(dir) - (10.0f + 60.0f * float(i)), 360.0f), 0.0f, 1e-3f);
    EXPECT_NEAR((a[size_t(i)]->frame.position - 0.1f * dir).norm(), 0.0f, 1e-6f);
  }
  ASSERT_EQ(b.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    Vec3 p = b[size_t(i)]->frame.position;
    EXPECT_NEAR(p.norm(), 0.5f, 1e-6f);
    EXPECT_NEAR(p.y(), 0.0f, 1e-6f);
    EXPECT_NEAR(std::remainder(azimuth(p) - 45.0f * float(i), 360.0f), 0.0f, 1e-3f);  // full ring: 360/n apart
    // Upright children leaning outward by the tilt.
    Vec3 dir = b[size_t(i)]->frame.rotation * Vec3::UnitY();
    EXPECT_NEAR(degrees(angleBetween(dir, Vec3::UnitY())), 20.0f, 1e-3f);
    EXPECT_GT(dir.dot(p), 0.0f);
  }
  ASSERT_EQ(c.size(), 5u);
  for (int i = 0; i < 5; ++i)  // an open arc: from the opening to the closing angle inclusive
    EXPECT_NEAR(std::remainder(azimuth(c[size_t(i)]->frame.position) - (30.0f + 30.0f * float(i)), 360.0f), 0.0f, 1e-3f);
}

TEST(GraphShapes, HornsWithASectionOrPrimitivesArePrimitivesOnTheirAnchor) {
  auto g = parse(R"j({"tendril_graph": 1, "root": {"links": ["stem"]}, "components": [
    {"name": "stem", "type": "tree",
     "params": {"length": 1, "segments": 4, "branches": 2, "branch_start": 0.5, "branch_end": 0.55},
     "links": [{"to": "fluted", "type": "branch"}, "beads"]},
    {"name": "fluted", "type": "horn",
     "params": {"length": 0.4, "segments": 5, "section": [[1, 0], [0, -0.6], [-1, 0], [0, 0.6]], "curvature": 30}},
    {"name": "beads", "type": "horn", "params": {"length": 0.3, "segments": 3, "primitive": "sphere"}}]})j");
  plant::PlantModel p = graph::generatePlant(g);
  EXPECT_EQ(p.nodeCount(), 4u);  // only the tube stem is skeleton
  size_t sections = 0, beads = 0;
  for (const plant::Primitive& pr : p.primitives) {
    const std::string& name = p.meshes[pr.mesh].name;
    if (name == "fluted") {
      ++sections;
      EXPECT_EQ(pr.node, 2);  // hangs from the stem node at half its length
    } else if (name == "beads") {
      ++beads;
      EXPECT_EQ(pr.node, 3);  // at the tip
    }
  }
  EXPECT_EQ(sections, 2u);
  EXPECT_EQ(beads, 3u);
  for (const plant::PrimitiveMesh& m : p.meshes) expectClean(m.mesh, m.name);
}

}  // namespace
}  // namespace tendril

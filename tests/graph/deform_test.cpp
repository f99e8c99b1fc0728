// Free-form deformations (seed 004, "Free-form deformations", Fig. 10; sidebar, FFD and
// Hyperpatch): what they move, what they leave alone, and that switched-off parts stay attached.
#include "graph_test_util.h"

#include "tendril/graph/deform.h"
#include "tendril/mesh/primitive_mesh.h"

namespace tendril {
namespace {

using graphtest::parse;

// World-space vertices of the primitives made by one component, in order.
std::vector<Vec3> primitiveVertices(const plant::PlantModel& p, const std::string& meshName) {
  std::vector<Vec3> out;
  for (const plant::Primitive& pr : p.primitives) {
    const plant::PrimitiveMesh& m = p.meshes[pr.mesh];
    if (m.name != meshName) continue;
    Mat4 world = mesh::worldFromNode(p, pr.node) * pr.nodeFromPrimitive;
    for (const Vec3& v : m.mesh.positions) out.push_back((world * v.homogeneous()).head<3>());
  }
  return out;
}

std::string graphWith(const std::string& outer, const std::string& inner) {
  return R"({"tendril_graph": 1, "root": {"links": [)" + outer + R"(]}, "components": [
    {"name": "bend", "type": "ffd", "params": {"x": "x + 0.5 * y * y", "z": "z + 0.2 * y"}, "links": ["a", "off"]},
    {"name": "off", "type": "ffd", "params": {"disable_previous": true}, "links": ["b"]},
    {"name": "a", "type": "simple", "params": {"shape": "cube", "size": [0.2, 1, 0.2], "translate": [0, 0.5, 0]}},
    {"name": "b", "type": "simple", "params": {"shape": "sphere", "size": [0.3, 0.3, 0.3], "translate": [0.5, 1, 0]}},
    {"name": "free", "type": "hydra", "params": {"count": 1, "angle": 0}, "links": ["a", )" +
         inner + R"(]}]})";
}

TEST(GraphDeform, AnFfdSwitchedOffForASubgraphLeavesItsVerticesUntouched) {
  // The same shapes with the FFD (via "bend") and without any deformer (via "free").
  plant::PlantModel deformed = graph::generatePlant(parse(graphWith(R"("bend")", R"("b")")));
  plant::PlantModel plain = graph::generatePlant(parse(graphWith(R"("free")", R"("b")")));
  std::vector<Vec3> a0 = primitiveVertices(plain, "a"), a1 = primitiveVertices(deformed, "a");
  std::vector<Vec3> b0 = primitiveVertices(plain, "b"), b1 = primitiveVertices(deformed, "b");
  ASSERT_EQ(a0.size(), a1.size());
  ASSERT_EQ(b0.size(), b1.size());
  ASSERT_FALSE(b0.empty());
  // "a" is deformed exactly by the functions ...
  float moved = 0.0f;
  for (size_t i = 0; i < a0.size(); ++i) {
    Vec3 expected(a0[i].x() + 0.5f * a0[i].y() * a0[i].y(), a0[i].y(), a0[i].z() + 0.2f * a0[i].y());
    EXPECT_NEAR((a1[i] - expected).norm(), 0.0f, 1e-5f);
    moved = std::max(moved, (a1[i] - a0[i]).norm());
  }
  EXPECT_GT(moved, 0.4f);
  // ... "b", below an FFD with disable_previous, is not moved at all.
  for (size_t i = 0; i < b0.size(); ++i) EXPECT_EQ(b1[i], b0[i]) << i;
}

TEST(GraphDeform, SkeletonModeMovesStemsAndCarriesLeavesUndeformed) {
  // seed 004, Fig. 10b: the twigs of a pine are deformed, the needles remain unchanged.
  const char* text = R"({"tendril_graph": 1, "root": {"links": ["%s"]}, "components": [
    {"name": "ffd", "type": "ffd", "params": {"mode": "%s", "x": "x + 0.3 * y * y"}, "links": ["twig"]},
    {"name": "twig", "type": "tree", "params": {"length": 1, "segments": 10, "branches": 8, "branch_start": 0.2},
     "links": [{"to": "needle", "type": "branch"}]},
    {"name": "needle", "type": "leaf", "params": {"size": 0.1, "aspect": 0.1}}]})";
  auto build = [&](const char* root, const char* mode) {
    char buf[2048];
    std::snprintf(buf, sizeof buf, text, root, mode);
    return graph::generatePlant(parse(buf));
  };
  plant::PlantModel plain = build("twig", "all");
  plant::PlantModel skeleton = build("ffd", "skeleton");
  plant::PlantModel all = build("ffd", "all");
  ASSERT_EQ(plain.nodeCount(), skeleton.nodeCount());
  // Skeleton points follow the function (segment starts and the tip).
  for (size_t i = 0; i < plain.nodeCount(); ++i) {
    Vec3 p = plain.position[i];
    EXPECT_NEAR((skeleton.position[i] - Vec3(p.x() + 0.3f * p.y() * p.y(), p.y(), p.z())).norm(), 0.0f, 1e-5f);
  }
  Vec3 tip = plain.tip(plain.nodeCount() - 1);
  EXPECT_NEAR((skeleton.tip(skeleton.nodeCount() - 1) - Vec3(tip.x() + 0.3f * tip.y() * tip.y(), tip.y(), tip.z())).norm(),
              0.0f, 1e-4f);
  // Needles keep their size and their frame relative to the node they hang from: they ride
  // along with the bent twig without being deformed themselves.
  ASSERT_EQ(plain.leafCount(), skeleton.leafCount());
  for (size_t i = 0; i < plain.leafCount(); ++i) {
    EXPECT_EQ(skeleton.leafSize[i], plain.leafSize[i]);
    EXPECT_EQ(skeleton.leafNode[i], plain.leafNode[i]);
    EXPECT_NEAR((skeleton.leafOffset[i] - plain.leafOffset[i]).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR(skeleton.leafRotation[i].angularDistance(plain.leafRotation[i]), 0.0f, 1e-5f);
  }
  // With mode "all" the needles are deformed too: sheared, those high up grow longer.
  bool grew = false;
  for (size_t i = 0; i < plain.leafCount(); ++i) grew = grew || all.leafSize[i] > plain.leafSize[i] * 1.01f;
  EXPECT_TRUE(grew);
}

TEST(GraphDeform, SwitchedOffBranchesStayAttachedToTheirDeformedParent) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["ffd"]}, "components": [
    {"name": "ffd", "type": "ffd", "params": {"mode": "skeleton", "x": "x + 0.4 * y"}, "links": ["trunk"]},
    {"name": "trunk", "type": "tree", "params": {"length": 2, "segments": 8, "branches": 3, "branch_start": 0.5},
     "links": [{"to": "off", "type": "branch"}]},
    {"name": "off", "type": "ffd", "params": {"disable_previous": true}, "links": ["limb"]},
    {"name": "limb", "type": "tree", "params": {"length": 0.6, "segments": 4}}]})");
  graph::ITree t = graph::expand(g);
  plant::PlantModel p = graph::buildPlant(t);
  int branches = 0;
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    if (!(p.flags[i] & plant::kNodeBranchStart)) continue;
    ++branches;
    // The limb's first node sits on its (deformed) parent segment: the distance from the
    // segment's line is zero and the limb keeps its length and shape.
    int32_t parent = p.parent[i];
    Vec3 a = p.position[size_t(parent)], d = p.direction(size_t(parent));
    Vec3 r = p.position[i] - a;
    EXPECT_NEAR((r - r.dot(d) * d).norm(), 0.0f, 1e-4f);
    EXPECT_NEAR(p.length[i], 0.6f / 4.0f, 1e-5f);
    EXPECT_NEAR(angleBetween(p.direction(i), p.direction(i + 1)), 0.0f, 1e-4f);  // still straight
  }
  EXPECT_EQ(branches, 3);
}

TEST(GraphDeform, HyperpatchIsABezierLattice) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["hp"]}, "components": [
    {"name": "hp", "type": "hyperpatch",
     "params": {"degree": 1, "size": [2, 2, 2], "points": [{"index": [1, 1, 1], "offset": [0, 0.8, 0]}]},
     "links": ["box"]},
    {"name": "box", "type": "simple", "params": {"shape": "cube", "size": [2, 2, 2]}}]})");
  graph::ITree t = graph::expand(g);
  ASSERT_EQ(t.deformers.size(), 1u);
  // The corner control point moves its corner by the full offset, the centre by 1/8 of it,
  // the opposite corner not at all.
  EXPECT_NEAR((graph::deformPoint(t, 0, Vec3(1, 2, 1)) - Vec3(1, 2.8f, 1)).norm(), 0.0f, 1e-6f);
  EXPECT_NEAR((graph::deformPoint(t, 0, Vec3(0, 1, 0)) - Vec3(0, 1.1f, 0)).norm(), 0.0f, 1e-6f);
  EXPECT_NEAR((graph::deformPoint(t, 0, Vec3(-1, 0, -1)) - Vec3(-1, 0, -1)).norm(), 0.0f, 1e-6f);
  // An undisplaced lattice of any degree is the identity.
  for (int degree = 1; degree <= 4; ++degree) {
    graph::Deformer d;
    d.degree = degree;
    d.size = Vec3(1, 2, 3);
    d.offsets.assign(size_t((degree + 1) * (degree + 1) * (degree + 1)), Vec3::Zero());
    EXPECT_EQ(graph::hyperpatchOffset(d, Vec3(0.1f, 0.7f, -0.4f)), Vec3::Zero());
  }
}

}  // namespace
}  // namespace tendril

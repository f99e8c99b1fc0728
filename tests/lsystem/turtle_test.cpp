// The turtle: exact geometry for simple strings (ABOP §1.3, §1.5, §2.4) and the PlantModel
// conventions (a node's local +Y is the heading, +Z the turtle's up vector).
#include "lsystem/lsystem_test_util.h"
#include "tendril/env/primitives.h"

#include <gtest/gtest.h>

namespace tendril::lsystem {
namespace {

using test::compile;

constexpr float kEps = 1e-5f;

plant::PlantModel draw(const std::string& text) {
  LSystem ls(compile(text), test::steps(0));
  return ls.interpret();
}

void expectVec(const Vec3& a, const Vec3& b, float eps = kEps) {
  EXPECT_NEAR(a.x(), b.x(), eps) << a.transpose() << " vs " << b.transpose();
  EXPECT_NEAR(a.y(), b.y(), eps) << a.transpose() << " vs " << b.transpose();
  EXPECT_NEAR(a.z(), b.z(), eps) << a.transpose() << " vs " << b.transpose();
}

// The values a query module holds after answering: ?X(...) at position `index`.
Vec3 queryAt(const LSystem& ls, size_t index) {
  const float* p = ls.string().paramsOf(index);
  return Vec3(p[0], p[1], p[2]);
}

TEST(Turtle, TurnLeftAndForward) {
  plant::PlantModel p = draw("angle: 90\naxiom: F + F(2)\n");
  ASSERT_EQ(p.nodeCount(), 2u);
  expectVec(p.position[0], Vec3(0, 0, 0));
  expectVec(p.direction(0), Vec3(0, 1, 0));
  EXPECT_FLOAT_EQ(p.length[0], 1.0f);
  expectVec(p.position[1], Vec3(0, 1, 0));
  expectVec(p.direction(1), Vec3(-1, 0, 0));  // + turns toward L, which starts at -X
  expectVec(p.tip(1), Vec3(-2, 1, 0));
  EXPECT_EQ(p.parent[1], 0);
  // Node frames: local +Y = heading, local +Z = up (+Z at the start, unchanged by +).
  expectVec(p.orientation[0] * Vec3::UnitZ(), Vec3(0, 0, 1));
  expectVec(p.orientation[1] * Vec3::UnitZ(), Vec3(0, 0, 1));
  expectVec(p.orientation[1] * Vec3::UnitX(), Vec3(0, 1, 0));
  EXPECT_FLOAT_EQ(p.radius[0], 0.05f);  // width 0.1 is the diameter
}

TEST(Turtle, EveryRotationModule) {
  struct Case {
    const char* modules;
    Vec3 h, u, l;
  };
  const Case cases[] = {
      {"+(90)", {-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},  {"-(90)", {1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {"&(90)", {0, 0, -1}, {0, 1, 0}, {-1, 0, 0}},  {"^(90)", {0, 0, 1}, {0, -1, 0}, {-1, 0, 0}},
      {"\\(90)", {0, 1, 0}, {1, 0, 0}, {0, 0, 1}},   {"/(90)", {0, 1, 0}, {-1, 0, 0}, {0, 0, -1}},
      {"|", {0, -1, 0}, {0, 0, 1}, {1, 0, 0}},        {"+ +", {0, -1, 0}, {0, 0, 1}, {1, 0, 0}},
      {"&(30) &(60)", {0, 0, -1}, {0, 1, 0}, {-1, 0, 0}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.modules);
    LSystem ls(compile(std::string("angle: 90\naxiom: ") + c.modules + " ?H(0,0,0) ?U(0,0,0) ?L(0,0,0)\n"),
               test::steps(0));
    ls.answerQueries();
    size_t n = ls.string().size();
    expectVec(queryAt(ls, n - 3), c.h);
    expectVec(queryAt(ls, n - 2), c.u);
    expectVec(queryAt(ls, n - 1), c.l);
  }
}

TEST(Turtle, DollarRollsLeftHorizontal) {
  LSystem ls(compile("axiom: &(40) \\(25) $ ?H(0,0,0) ?L(0,0,0) ?U(0,0,0)\n"), test::steps(0));
  ls.answerQueries();
  Vec3 h = queryAt(ls, 3), l = queryAt(ls, 4), u = queryAt(ls, 5);
  // ABOP §1.5: L = V × H / |V × H|, U = H × L; H itself is unchanged by the roll.
  expectVec(h, Vec3(0, std::cos(radians(40.0f)), -std::sin(radians(40.0f))));
  expectVec(l, Vec3::UnitY().cross(h).normalized());
  expectVec(u, h.cross(l));
  EXPECT_NEAR(l.y(), 0.0f, kEps);
}

TEST(Turtle, BranchesParentsOrdersAndChains) {
  plant::PlantModel p = draw("angle: 90\naxiom: F [+F F] F [-F] f F\n");
  ASSERT_EQ(p.nodeCount(), 6u);
  EXPECT_EQ(p.parent[1], 0);
  EXPECT_EQ(p.order[1], 1);
  EXPECT_TRUE(p.flags[1] & plant::kNodeBranchStart);
  EXPECT_EQ(p.parent[2], 1);
  EXPECT_FALSE(p.flags[2] & plant::kNodeBranchStart);
  EXPECT_EQ(p.parent[3], 0);  // after ] the turtle is back on the main axis
  EXPECT_EQ(p.order[3], 0);
  EXPECT_FALSE(p.flags[3] & plant::kNodeBranchStart);
  expectVec(p.position[3], Vec3(0, 1, 0));
  EXPECT_EQ(p.parent[4], 3);
  expectVec(p.direction(4), Vec3(1, 0, 0));
  // f leaves a gap: the next segment hangs on the last one but starts its own chain.
  EXPECT_EQ(p.parent[5], 3);
  EXPECT_TRUE(p.flags[5] & plant::kNodeBranchStart);
  expectVec(p.position[5], Vec3(0, 3, 0));
}

TEST(Turtle, WidthModules) {
  plant::PlantModel p = draw("width factor: 0.5\naxiom: !(0.5) F(2) ! F !(0.1) F\n");
  ASSERT_EQ(p.nodeCount(), 3u);
  EXPECT_FLOAT_EQ(p.radius[0], 0.25f);
  EXPECT_FLOAT_EQ(p.length[0], 2.0f);
  EXPECT_FLOAT_EQ(p.radius[1], 0.125f);
  EXPECT_FLOAT_EQ(p.radius[2], 0.05f);
}

TEST(Turtle, TropismBendsTheHeadingByElasticityTimesTheSine) {
  // ABOP §2.4: after F, the heading turns about H × T by α = e·|H × T|.
  plant::PlantModel p = draw("tropism: 1, 0, 0\nelasticity: 0.3\naxiom: F F @Te(0) F\n");
  ASSERT_EQ(p.nodeCount(), 3u);
  expectVec(p.direction(0), Vec3(0, 1, 0));
  expectVec(p.direction(1), Vec3(std::sin(0.3f), std::cos(0.3f), 0));
  float s = std::cos(0.3f);  // |H × T| for the second segment
  float a = 0.3f + 0.3f * s;
  expectVec(p.direction(2), Vec3(std::sin(a), std::cos(a), 0));
  // @Tv changes T; elasticity 0 stops the bending (the third F kept the second's end heading).
  plant::PlantModel q = draw("elasticity: 0.5\naxiom: @Tv(0, 0, 2) F F\n");
  expectVec(q.direction(1), Vec3(0, std::cos(1.0f), std::sin(1.0f)));
}

TEST(Turtle, LeavesHangOnTheLastSegmentInTheTurtleFrame) {
  plant::PlantModel p = draw("angle: 90\naxiom: F F ~leaf(0.5, 0, 0.1) [+ ~leaf(0.25)] &(90) ~leaf(0.3)\n");
  ASSERT_EQ(p.nodeCount(), 2u);
  ASSERT_EQ(p.leafCount(), 3u);
  EXPECT_EQ(p.leafNode[0], 1);
  expectVec(p.leafWorldPosition(0), Vec3(0, 2, 0));
  expectVec(p.leafOffset[0], Vec3(0, 1, 0));
  EXPECT_FLOAT_EQ(p.leafSize[0], 0.5f);
  EXPECT_FLOAT_EQ(p.leafPetiole[0], 0.1f);
  // The blade runs along H, its upper side faces U.
  expectVec(p.leafWorldRotation(0) * Vec3::UnitY(), Vec3(0, 1, 0));
  expectVec(p.leafWorldRotation(0) * Vec3::UnitZ(), Vec3(0, 0, 1));
  expectVec(p.leafWorldRotation(1) * Vec3::UnitY(), Vec3(-1, 0, 0));
  expectVec(p.leafWorldRotation(2) * Vec3::UnitY(), Vec3(0, 0, -1));
  expectVec(p.leafWorldRotation(2) * Vec3::UnitZ(), Vec3(0, 1, 0));
  EXPECT_TRUE(p.flags[1] & plant::kNodeLeafNode);
  plant::validate(p, "test");
}

TEST(Turtle, PolygonsAndSurfaces) {
  plant::PlantModel p = draw("angle: 90\nsurface: tri = { . f . + f . }\naxiom: [{ . f . + f . f . }] F ' ~tri(2)\n");
  // Colour 0: the polygon; colour 1: the surface (its colours count from the turtle's).
  ASSERT_EQ(p.meshes.size(), 2u);
  const TriangleMesh& quad = p.meshes[0].mesh;
  // Four vertices (0,0) (0,1) (-1,1) (-2,1): two triangles per side, two sides.
  EXPECT_EQ(quad.vertexCount(), 8u);
  EXPECT_EQ(quad.triangleCount(), 4u);
  double area = 0;
  for (size_t t = 0; t < quad.triangleCount(); ++t) {
    const Vec3& a = quad.positions[quad.indices[3 * t]];
    const Vec3& b = quad.positions[quad.indices[3 * t + 1]];
    const Vec3& c = quad.positions[quad.indices[3 * t + 2]];
    Vec3 n = (b - a).cross(c - a);
    area += 0.5 * n.norm();
    // Front faces wind counter-clockwise about their normal.
    EXPECT_GT(n.dot(quad.normals[quad.indices[3 * t]]), 0.0f);
  }
  EXPECT_NEAR(area, 2 * 1.0, 1e-5);  // a trapezoid of area 1, drawn on both sides
  // The surface is the triangle (0,0) (0,1) (-1,1) scaled by 2 at the turtle (0, 1, 0) after F.
  const TriangleMesh& tri = p.meshes[1].mesh;
  ASSERT_EQ(tri.vertexCount(), 6u);
  expectVec(tri.positions[0], Vec3(0, 1, 0));
  expectVec(tri.positions[1], Vec3(0, 3, 0));
  expectVec(tri.positions[2], Vec3(-2, 3, 0));
  EXPECT_EQ(p.primitives.size(), 2u);
  plant::validate(p, "test");
}

TEST(Turtle, SetHeadingMoveToClimbingAndSpheres) {
  plant::PlantModel p = draw("axiom: @R(1, 0, 0, 0, 1, 1) @Climb(1) F @M(5, 5, 5) @Climb(0) F @O(0.5)\n");
  ASSERT_EQ(p.nodeCount(), 2u);
  expectVec(p.direction(0), Vec3(1, 0, 0));
  expectVec(p.orientation[0] * Vec3::UnitZ(), Vec3(0, 1, 1).normalized());
  EXPECT_TRUE(p.flags[0] & plant::kNodeClimbing);
  EXPECT_FALSE(p.flags[1] & plant::kNodeClimbing);
  expectVec(p.position[1], Vec3(5, 5, 5));
  ASSERT_EQ(p.meshes.size(), 1u);
  for (const Vec3& v : p.meshes[0].mesh.positions) EXPECT_NEAR((v - Vec3(6, 5, 5)).norm(), 0.5f, 1e-5f);
}

TEST(Turtle, InterpretationRulesDrawWithoutChangingTheString) {
  LSystem ls(compile(R"(
derivation length: 2
axiom: A(1)
A(x) -> A(x + 1)
interpretation:
maximum depth: 2
A(x) -> B(x) B(x)
B(x) -> F(x)
)"));
  ls.derive();
  EXPECT_EQ(ls.text(), "A(3)");
  plant::PlantModel p = ls.interpret();
  ASSERT_EQ(p.nodeCount(), 2u);
  expectVec(p.tip(1), Vec3(0, 6, 0));
}

TEST(Turtle, NodeAgesCountStepsSinceTheSegmentWasProduced) {
  LSystem ls(compile("derivation length: 3\naxiom: A\nA -> F A\n"), test::stepTime(0.5f));
  ls.derive();
  plant::PlantModel p = ls.interpret();
  ASSERT_EQ(p.nodeCount(), 3u);
  EXPECT_FLOAT_EQ(p.age[0], 1.0f);  // made in step 1, now step 3
  EXPECT_FLOAT_EQ(p.age[2], 0.0f);
}

TEST(Turtle, QueriesReportThePositionAndFrame) {
  LSystem ls(compile("angle: 90\naxiom: F(2) + F ?P(0, 0, 0) A\n?P(x, y, z) < A -> B(x, y, z)\n"),
             test::steps(1));
  ls.step();  // the queries are answered before the production reads them
  EXPECT_EQ(ls.text(), "F(2)+F ?P(-1, 2, 0) B(-1, 2, 0)");
}

TEST(Turtle, EnvironmentQueries) {
  env::Environment e;
  env::ObstacleDef wall;
  wall.name = "wall";
  wall.mesh = env::makeBox(Vec3(4, 4, 0.2f));
  wall.worldFromLocal.translation = Vec3(0, 0, -0.1f);  // front face at z = 0
  e.addObstacle(wall);
  env::Light sun;
  sun.direction = Vec3(0, 0, -1);  // shining onto the front face
  e.addLight(sun);
  env::Stroke s;
  s.points = {Vec3(0.5f, 0.3f, 0.3f)};
  s.radius = 1.0f;
  e.addStroke(s);
  e.commit();
  // The turtle stands 0.3 m in front of the wall, heading into it (-Z).
  LSystem ls(compile("axiom: @M(0, 0.3, 0.3) @R(0, 0, -1) ?E(SURFACE, 1, 0, 0, 0, 0) ?E(HIT, 2, 0, 0, 0, 0) "
                     "?E(HIT, 0.1, 0, 0, 0, 0) ?E(LIGHT, 0, 0, 0, 0) ?E(ATTRACT, 0, 0, 0) ?E(SURFACE, 0.1, 5) "
                     "?E(FACING, 1, 50, 0, 0, 0, 0) @R(0, 0, 1) ?E(FACING, 1, 50, 0, 0, 0, 0) "
                     "@R(0, 1, 0) ?E(FACING, 1, 50, 0, 0, 0, 0)\n"),
             test::steps(0));
  ls.answerQueries(&e);
  const LString& str = ls.string();
  auto q = [&](size_t i) { return str.paramsOf(i); };
  EXPECT_NEAR(q(2)[2], 0.3f, 1e-4f);  // distance to the wall
  expectVec(Vec3(q(2)[3], q(2)[4], q(2)[5]), Vec3(0, 0, 1));
  EXPECT_NEAR(q(3)[2], 0.3f, 1e-4f);  // the ray ahead hits it at 0.3
  expectVec(Vec3(q(3)[3], q(3)[4], q(3)[5]), Vec3(0, 0, 1));  // the normal facing the turtle
  EXPECT_EQ(q(4)[2], -1.0f);          // nothing within 0.1 ahead
  EXPECT_FLOAT_EQ(q(5)[1], 1.0f);     // in full sun
  expectVec(Vec3(q(5)[2], q(5)[3], q(5)[4]), Vec3(0, 0, 1));
  Vec3 pull = e.attraction(Vec3(0, 0.3f, 0.3f));
  EXPECT_GT(pull.x(), 0.0f);  // toward the stroke point
  expectVec(Vec3(q(6)[1], q(6)[2], q(6)[3]), pull);
  EXPECT_EQ(q(7)[2], -1.0f);  // no surface within 0.1
  // FACING ignores the surfaces the turtle grows away from (normal within 50 degrees of H).
  EXPECT_NEAR(q(8)[3], 0.3f, 1e-4f);  // heading into the wall: it holds
  expectVec(Vec3(q(8)[4], q(8)[5], q(8)[6]), Vec3(0, 0, 1));
  EXPECT_EQ(q(10)[3], -1.0f);  // heading straight away from it: ignored (the back face too)
  EXPECT_NEAR(q(12)[3], 0.3f, 1e-4f);  // heading up along it: it holds
  expectVec(Vec3(q(12)[4], q(12)[5], q(12)[6]), Vec3(0, 0, 1));
  // Without an environment every query answers "nothing".
  ls.answerQueries(nullptr);
  EXPECT_EQ(q(2)[2], -1.0f);
  EXPECT_EQ(q(3)[2], -1.0f);
  EXPECT_EQ(q(5)[1], 0.0f);
}

}  // namespace
}  // namespace tendril::lsystem

// Tropisms of Tree and Horn stems and the World's fields (seed 004, "Tropisms", Fig. 9):
// each bends stems toward (or away from) its field vector.
#include "graph_test_util.h"

#include <cmath>

namespace tendril {
namespace {

using graphtest::parse;

// A single stem under an optional World; returns its skeleton.
plant::PlantModel stem(const std::string& stemParams, const std::string& worldParams = "") {
  std::string root = worldParams.empty() ? R"(["s"])" : R"(["w"])";
  std::string world = worldParams.empty()
                          ? std::string()
                          : R"({"name": "w", "type": "world", "params": )" + worldParams + R"(, "links": ["s"]},)";
  return graph::generatePlant(parse(R"({"tendril_graph": 1, "root": {"links": )" + root + R"(}, "components": [)" +
                                    world + R"({"name": "s", "type": "horn", "params": )" + stemParams + "}]}"));
}

Vec3 tipOf(const plant::PlantModel& p) { return p.tip(p.nodeCount() - 1); }

TEST(GraphTropism, GravitropismBendsStemsTowardGravityOrAway) {
  // Horizontal stems along +X.
  const std::string base = R"("length": 1, "segments": 20, "rotate": [0, 0, -90])";
  Vec3 straight = tipOf(stem("{" + base + "}"));
  EXPECT_NEAR(straight.y(), 0.0f, 1e-5f);
  Vec3 down = tipOf(stem("{" + base + R"(, "gravitropism": 1.5})"));
  Vec3 up = tipOf(stem("{" + base + R"(, "gravitropism": -1.5})"));
  EXPECT_LT(down.y(), -0.2f);
  EXPECT_GT(up.y(), 0.2f);
  EXPECT_NEAR(down.y(), -up.y(), 1e-4f);  // symmetric about the horizontal
  // The bend is monotonic along the stem: every segment points at least as far down as the last.
  plant::PlantModel p = stem("{" + base + R"(, "gravitropism": 3})");
  for (size_t i = 1; i < p.nodeCount(); ++i) EXPECT_LE(p.direction(i).y(), p.direction(i - 1).y() + 1e-6f);
  // A strong gravitropism never turns the stem past the field: the stem hangs, it does not curl.
  plant::PlantModel hanging = stem("{" + base + R"(, "gravitropism": 40})");
  for (size_t i = 0; i < hanging.nodeCount(); ++i) EXPECT_GE(hanging.direction(i).x(), -1e-4f);
  EXPECT_NEAR(hanging.direction(hanging.nodeCount() - 1).y(), -1.0f, 1e-3f);
}

TEST(GraphTropism, PhototropismFollowsTheWorldsLightField) {
  // A vertical stem and light from +X (a World replaces the default +Y light field).
  const std::string base = R"({"length": 1, "segments": 20, "phototropism": 2})";
  Vec3 tip = tipOf(stem(base, R"({"light": [1, 0, 0]})"));
  EXPECT_GT(tip.x(), 0.3f);
  EXPECT_NEAR(tip.z(), 0.0f, 1e-5f);
  // A negative phototropism turns the stem away from the light by the same amount.
  Vec3 away = tipOf(stem(R"({"length": 1, "segments": 20, "phototropism": -2})", R"({"light": [1, 0, 0]})"));
  EXPECT_NEAR(away.x(), -tip.x(), 1e-4f);
  EXPECT_NEAR(away.y(), tip.y(), 1e-4f);
  // A field given as functions of the position: light from a point at (0, 1, -3).
  Vec3 toward = tipOf(stem(base, R"({"light": ["-x", "1 - y", "-3 - z"]})"));
  EXPECT_LT(toward.z(), -0.2f);
  EXPECT_NEAR(toward.x(), 0.0f, 1e-4f);
  // The default light field is +Y: a vertical stem stays straight.
  Vec3 straight = tipOf(stem(base));
  EXPECT_NEAR(straight.x(), 0.0f, 1e-5f);
  EXPECT_NEAR(straight.y(), 1.0f, 1e-5f);
}

TEST(GraphTropism, WindIsAHorizontalTropism) {
  const std::string base = R"({"length": 1, "segments": 20})";
  // Wind from the World toward +Z (wind_direction -90: +X turned -90° about +Y).
  plant::PlantModel p = stem(base, R"({"wind": 2, "wind_direction": -90})");
  Vec3 tip = tipOf(p);
  EXPECT_GT(tip.z(), 0.3f);
  EXPECT_NEAR(tip.x(), 0.0f, 1e-4f);
  // Horizontal: the stem leans over but never points below the horizon.
  plant::PlantModel strong = stem(base, R"({"wind": 30, "wind_direction": -90})");
  for (size_t i = 0; i < strong.nodeCount(); ++i) EXPECT_GE(strong.direction(i).y(), -1e-4f);
  // A stem with no flexibility ignores the wind.
  Vec3 stiff = tipOf(stem(R"({"length": 1, "segments": 20, "flexibility": 0})", R"({"wind": 2})"));
  EXPECT_NEAR(stiff.y(), 1.0f, 1e-5f);
}

TEST(GraphTropism, CylindricalTropismWindsStemsAroundAStick) {
  // seed 004, Fig. 9b: a stem started beside a stick of radius 4 cm winds around it and climbs.
  plant::PlantModel p = stem(R"({"length": 3, "segments": 150, "translate": [0.06, 0, 0]})",
                             R"({"cylinder_radius": 0.04, "cylinder_strength": 80, "cylinder_pitch": 30})");
  double turned = 0.0;
  float prevAngle = std::atan2(p.position[0].z(), p.position[0].x());
  size_t settled = 0, near = 0;
  for (size_t i = 1; i < p.nodeCount(); ++i) {
    Vec3 q = p.position[i];
    float a = std::atan2(q.z(), q.x());
    turned += std::remainder(double(a - prevAngle), 2.0 * M_PI);
    prevAngle = a;
    EXPECT_GE(p.direction(i).y(), -1e-3f);  // always climbing or level
    if (i > p.nodeCount() / 4) {
      ++settled;
      float rho = std::hypot(q.x(), q.z());
      if (rho > 0.025f && rho < 0.07f) ++near;
    }
  }
  EXPECT_GT(std::abs(turned), 4.0 * M_PI);       // at least two turns around the stick
  EXPECT_GT(near, settled * 9 / 10);              // and it stays close to its surface
  EXPECT_GT(tipOf(p).y(), 0.8f);                  // while climbing
  // Without the World the stem grows straight up.
  EXPECT_NEAR(tipOf(stem(R"({"length": 3, "segments": 150, "translate": [0.06, 0, 0]})")).x(), 0.06f, 1e-5f);
}

TEST(GraphTropism, LeavesTurnTowardTheLight) {
  auto g = parse(R"({"tendril_graph": 1, "root": {"links": ["w"]}, "components": [
    {"name": "w", "type": "world", "params": {"light": [1, 0, 0]}, "links": ["a", "b"]},
    {"name": "a", "type": "leaf", "params": {"phototropism": 1}},
    {"name": "b", "type": "leaf", "params": {"phototropism": 0.5}}]})");
  graph::ITree t = graph::expand(g);
  ASSERT_EQ(t.leaves.size(), 2u);
  // An upright leaf's normal is +Z; fully phototropic it faces the light, half way half as far.
  EXPECT_NEAR((t.leaves[0].frame.rotation * Vec3::UnitZ() - Vec3::UnitX()).norm(), 0.0f, 1e-5f);
  EXPECT_NEAR(degrees(angleBetween(t.leaves[1].frame.rotation * Vec3::UnitZ(), Vec3::UnitX())), 45.0f, 1e-3f);
}

}  // namespace
}  // namespace tendril

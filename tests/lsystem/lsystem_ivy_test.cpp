// Seed 003's ivy written as a grammar (examples/grammars/japanese-ivy.ls) grows on the
// foundation's scenes and passes the same checks as the climbing model: no segment through an
// obstacle, no leaf corner behind a surface, leaves facing away from their support, and climbing
// segments within the adhesion distance.
#include "lsystem/lsystem_test_util.h"
#include "support/climb_checks.h"
#include "support/determinism.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace tendril::lsystem {
namespace {

constexpr float kAdhesion = 0.08f;  // the grammar's REACH

const char* kGround = R"({"name": "ground", "type": "plane", "size": [10, 10]})";
const char* kSun = R"({"type": "directional", "direction": [-0.1, -1, -0.4]})";

std::string ivy(const std::string& name, const std::string& position, int seed, const std::string& extra = "") {
  return R"({"name": ")" + name + R"(", "model": "lsystem", "grammar": "japanese-ivy", "position": )" + position +
         R"(, "seed": )" + std::to_string(seed) + extra + "}";
}

std::unique_ptr<session::Session> grow(const std::string& sceneJson, int steps,
                                       const std::filesystem::path& baseDir = tendril::test::sourceDir()) {
  scene::Scene s = scene::parseScene(parseJson(sceneJson, "test scene"), "test scene", baseDir);
  auto session = std::make_unique<session::Session>(std::move(s));
  session->run(uint32_t(steps));
  return session;
}

// Returns the number of segments checked.
size_t expectClean(const session::Session& s) {
  size_t total = 0;
  for (const plant::PlantModel& p : s.plants()) {
    SCOPED_TRACE(p.name);
    plant::validate(p, p.name);
    tendril::test::ClimbReport r = tendril::test::checkClimbingPlant(p, s.environment(), kAdhesion);
    total += r.segments;
    EXPECT_EQ(r.crossings, 0u) << "segments through an obstacle";
    EXPECT_EQ(r.insideSegments, 0u);
    EXPECT_EQ(r.leafCornersBehind, 0u) << "of " << 4 * r.leaves << " leaf corners";
    EXPECT_EQ(r.leavesFacingSurface, 0u) << "of " << r.leaves << " leaves";
    EXPECT_GE(r.nearFraction(), 0.95) << r.nearSurface << " of " << r.climbingSegments;
    EXPECT_GT(r.climbingSegments, 50u);
    EXPECT_GT(r.leaves, 0u);
  }
  return total;
}

TEST(LSystemIvy, ClimbsAWallOverSeveralSeeds) {
  for (int seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    auto s = grow(std::string(R"({"tendril": 1, "seed": 3, "environment": {"obstacles": [)") + kGround +
                      R"(, {"name": "wall", "type": "wall", "size": [3, 2.5, 0.2]}], "lights": [)" + kSun +
                      R"(]}, "plants": [)" + ivy("ivy", "[0, 0, 0.15]", seed) + "]}",
                  260);
    EXPECT_GT(expectClean(*s), 300u);
    // It climbed: part of the plant is well up the wall.
    EXPECT_GT(plant::computeStats(s->plants()[0]).bounds.max.y(), 1.2f);
  }
}

TEST(LSystemIvy, BoxSphereAndAWindow) {
  for (int seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    auto s = grow(std::string(R"({"tendril": 1, "seed": 5, "environment": {"obstacles": [)") + kGround +
                      R"(, {"name": "box", "type": "box", "size": [1, 1.2, 1], "position": [0, 0.6, 0],
                            "rotation": [0, 30, 0]},
                         {"name": "ball", "type": "sphere", "radius": 0.6, "position": [2, 0.6, 0]},
                         {"name": "wall", "type": "wall", "size": [3, 2.5, 0.25], "position": [5, 0, 0],
                          "openings": [{"center": [0, 1.0], "size": [1.0, 0.8]}]}],
                       "lights": [)" + kSun + R"(]},
                   "plants": [)" + ivy("on-box", "[0.27, 0, 0.47]", seed) + ", " +
                      ivy("on-ball", "[2, 0.5, 0.62]", seed) + ", " + ivy("under-window", "[5, 0, 0.15]", seed) +
                      "]}",
                  220);
    expectClean(*s);
    auto plants = s->plants();
    EXPECT_GT(plant::computeStats(plants[0]).bounds.max.y(), 1.0f);  // up the box
  }
}

TEST(LSystemIvy, AConcaveMeshFromAFile) {
  // The climbing model's torus: one ivy seeded in its hole, one outside leaning toward it.
  auto dir = tendril::test::scratchDir();
  tendril::test::writeTorusObj(dir / "torus.obj", 0.8f, 0.35f, 64, 32);
  for (int seed = 1; seed <= 2; ++seed) {
    SCOPED_TRACE(seed);
    auto s = grow(std::string(R"({"tendril": 1, "seed": 9, "environment": {"obstacles": [)") + kGround +
                      R"(, {"name": "torus", "type": "mesh", "path": "torus.obj", "position": [0, 0.35, 0]}],
                       "lights": [)" + kSun + R"(]}, "plants": [)" + ivy("in-hole", "[0.6, 0, 0]", seed) + ", " +
                      ivy("outside", "[0, 0, 1.0]", seed, R"(, "direction": [0, 1, -0.2])") + "]}",
                  220, dir);
    EXPECT_TRUE(s->environment().obstacle(1).closed);
    expectClean(*s);
  }
}

TEST(LSystemIvy, WrapsOverAThinWallAndGrowsDownItsBack) {
  // As for the climbing model: a wall 4 cm thick (thinner than the adhesion distance), 80 cm
  // high, sun in front. The ivy climbs the front, follows the top edge and hangs down the back
  // — never through the wall.
  for (int seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    auto s = grow(std::string(R"({"tendril": 1, "seed": 4, "environment": {"obstacles": [)") + kGround +
                      R"(, {"name": "wall", "type": "wall", "size": [2.5, 0.8, 0.04]}],
                       "lights": [{"type": "directional", "direction": [0, -1, -0.6]}]}, "plants": [)" +
                      ivy("ivy", "[0, 0, 0.06]", seed) + "]}",
                  240);
    expectClean(*s);
    plant::PlantModel p = s->plants()[0];
    size_t onTop = 0;
    float lowestBehind = 10.0f;
    for (size_t i = 0; i < p.nodeCount(); ++i) {
      Vec3 t = p.tip(i);
      onTop += t.y() > 0.8f && std::abs(t.z()) < 0.03f && std::abs(t.x()) < 1.2f;
      if (t.z() < -0.02f && std::abs(t.x()) < 1.0f) lowestBehind = std::min(lowestBehind, t.y());
    }
    EXPECT_GT(onTop, 50u) << "segments along the top edge";
    EXPECT_LT(lowestBehind, 0.6f) << "at least 20 cm down the back";
  }
}

TEST(LSystemIvy, FramesAndLeavesFollowTheSupport) {
  auto s = grow(std::string(R"({"tendril": 1, "seed": 3, "environment": {"obstacles": [)") + kGround +
                    R"(, {"name": "wall", "type": "wall", "size": [3, 2.5, 0.2]}]},
                    "plants": [)" + ivy("ivy", "[0, 0, 0.15]", 2) + "]}",
                200);
  plant::PlantModel p = s->plants()[0];
  const env::Environment& e = s->environment();
  // Climbing segments: local +Y is the growth direction, local +Z faces away from the support.
  size_t climbing = 0, facing = 0;
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    if (!(p.flags[i] & plant::kNodeClimbing)) continue;
    auto sp = e.closestPoint(p.tip(i), kAdhesion);
    if (!sp) continue;
    ++climbing;
    facing += (p.orientation[i] * Vec3::UnitZ()).dot(sp->away) > 0.7f;
  }
  ASSERT_GT(climbing, 100u);
  EXPECT_GE(double(facing) / double(climbing), 0.95) << facing << " of " << climbing;
  // Leaves within reach of a surface lie parallel to it, upper side away from it.
  size_t near = 0, parallel = 0;
  for (size_t l = 0; l < p.leafCount(); ++l) {
    auto sp = e.closestPoint(p.leafWorldPosition(l), kAdhesion);
    if (!sp) continue;
    ++near;
    parallel += (p.leafWorldRotation(l) * Vec3::UnitZ()).dot(sp->away) > 0.999f;
  }
  ASSERT_GT(near, 100u);
  EXPECT_EQ(parallel, near);
}

TEST(LSystemIvy, SameSceneSameResultForAnyThreadCount) {
  std::string scene = std::string(R"({"tendril": 1, "seed": 21, "environment": {"obstacles": [)") + kGround +
                      R"(, {"name": "wall", "type": "wall", "size": [4, 3, 0.2],
                            "openings": [{"center": [0.5, 1.5], "size": [1, 1]}]}], "lights": [)" + kSun +
                      R"(]}, "plants": [)" + ivy("a", "[-1, 0, 0.13]", 1) + ", " + ivy("b", "[1, 0, 0.13]", 2) +
                      "]}";
  const uint64_t one = tendril::test::sameAtEveryThreadCount([&] { return plant::contentHash(grow(scene, 150)->plants()); });
  std::string other = scene;
  other.replace(other.find("\"seed\": 21"), 10, "\"seed\": 22");
  EXPECT_NE(plant::contentHash(grow(other, 150)->plants()), one);
}

TEST(LSystemIvy, TheExampleSceneGrows) {
  scene::Scene sc = scene::loadScene(tendril::test::sourceDir() / "examples" / "scenes" / "ivy-lsystem.json");
  ASSERT_EQ(sc.plants.size(), 2u);
  EXPECT_EQ(sc.plants[0].model, "lsystem");
  session::Session s(std::move(sc));
  s.run(200);
  expectClean(s);
}

}  // namespace
}  // namespace tendril::lsystem

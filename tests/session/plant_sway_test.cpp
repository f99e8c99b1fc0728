// session::PlantSway: the plants of a Session growing and moving in the wind at once (seed 001),
// as the studio's viewport runs them.
#include "support/determinism.h"
#include "support/test_paths.h"
#include "tendril/core/hash.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_sway.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

// A free-standing L-system plant and a climbing ivy on a wall, in a gusty wind along the wall.
std::unique_ptr<session::Session> windySession() {
  const std::string json = R"({"tendril": 1, "seed": 2, "steps": 40,
    "environment": {"obstacles": [
        {"name": "ground", "type": "plane", "size": [10, 10]},
        {"name": "wall", "type": "wall", "size": [4, 2.5, 0.2]}],
      "lights": [{"type": "directional", "direction": [-0.1, -1, -0.4]}],
      "wind": {"mode": "gusty", "velocity": [9, 0, 2], "gust_strength": 0.6, "gust_period": 1.5}},
    "plants": [{"name": "ivy", "position": [0, 0, 0.15], "species": {"base": "japanese-ivy"}},
               {"name": "lychnis", "model": "lsystem", "grammar": "examples/grammars/abop-1.24a.ls", "position": [1.2, 0, 1.5]}]})";
  return std::make_unique<session::Session>(
      scene::parseScene(parseJson(json, "test scene"), "test scene", test::sourceDir()));
}

TEST(PlantSway, GrowingPlantsSwayTheSameAtEveryThreadCount) {
  // 30 frames of growing one step and swaying one frame: the posed plants hash the same at
  // 1, 2, 3 and 8 threads, and they do move.
  double moved = 0;
  test::sameAtEveryThreadCount([&] {
    std::unique_ptr<session::Session> s = windySession();
    session::PlantSway sway;
    Hasher h;
    for (int f = 0; f < 30; ++f) {
      s->step();
      std::vector<plant::PlantModel> plants = s->plants();
      const std::vector<plant::PlantModel> rest = plants;
      sway.pose(*s, plants, float(f) / 60.0f, 1.0f / 60.0f);
      for (size_t p = 0; p < plants.size(); ++p) {
        h.add(plant::contentHash(plants[p]));
        for (size_t i = 0; i < plants[p].nodeCount(); ++i)
          moved = std::max(moved, double((plants[p].position[i] - rest[p].position[i]).norm()));
      }
    }
    return h.digest();
  });
  EXPECT_GT(moved, 1e-3) << "the L-system plant sways";
}

TEST(PlantSway, APlantThatGrowsCarriesOnSwayingFromWhereItWas) {
  // The swing of every node survives the plant's growth (WindMotion::setRest): the nodes that
  // were there keep their rotation and rate; a fresh motion would start them from rest.
  std::unique_ptr<session::Session> s = windySession();
  session::PlantSway sway;
  for (int f = 0; f < 20; ++f) {
    s->step();
    std::vector<plant::PlantModel> plants = s->plants();
    sway.pose(*s, plants, float(f) / 60.0f, 1.0f / 60.0f);
  }
  const wind::WindMotion* before = sway.motion(1);
  ASSERT_NE(before, nullptr);
  const size_t nodes = before->rest().nodeCount();
  std::vector<Vec3> theta, omega;
  for (size_t i = 0; i < nodes; ++i) theta.push_back(before->swayVector(i)), omega.push_back(before->swayVelocity(i));
  double swinging = 0;
  for (const Vec3& w : omega) swinging = std::max(swinging, double(w.norm()));
  ASSERT_GT(swinging, 0.0);
  wind::WindMotion carried = *before;
  plant::PlantModel grown = before->rest();
  plant::PlantModel::NodeDef d;
  d.position = grown.tip(nodes - 1);
  d.orientation = grown.orientation[nodes - 1];
  d.length = 0.01f;
  d.radius = 0.001f;
  d.parent = int32_t(nodes - 1);
  grown.addNode(d);
  carried.setRest(grown);
  for (size_t i = 0; i < nodes; ++i) {
    ASSERT_EQ(carried.swayVector(i), theta[i]) << "node " << i;
    ASSERT_EQ(carried.swayVelocity(i), omega[i]) << "node " << i;
  }
  EXPECT_EQ(carried.swayVector(nodes), Vec3::Zero());
}

}  // namespace
}  // namespace tendril

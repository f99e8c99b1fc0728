// One rule for where a plant may start (env/seed_check.h), the same for every model: a seed
// inside an obstacle, or on a surface growing into an obstacle (the foot of a wall standing on
// the ground), is refused with the same message at the plant's "position"; a seed on a surface
// growing away from it or along it is not.
#include "session/session_test_util.h"

#include "tendril/core/error.h"
#include "tendril/env/seed_check.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

// One plant of `model` (its own keys in `keys`) at `position` growing along `direction`, on the
// ground, a wall standing on it at the origin (front face z = 0.1) and a box.
std::string scene(const std::string& keys, const std::string& position, const std::string& direction) {
  return R"({"tendril": 1, "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [4, 4]},
      {"name": "wall", "type": "wall", "size": [2, 1.5, 0.2]},
      {"name": "crate", "type": "box", "size": [0.4, 0.4, 0.4], "position": [1.5, 0.2, 1]}]},
      "plants": [{"name": "p", )" +
         keys + R"(, "position": )" + position + R"(, "direction": )" + direction + "}]}";
}

struct Model {
  const char* name;
  std::string keys;
};

const Model kModels[] = {
    {"climb", R"("model": "climb")"},
    {"particles", R"("model": "particles", "species": "ivy-particles")"},
    {"lsystem", R"("model": "lsystem", "grammar": "examples/grammars/abop-1.24a.ls", "derivation_length": 2)"},
    {"graph", R"("model": "graph", "graph": "examples/graphs/fig2.json")"},
};

std::string openError(const std::string& json) {
  try {
    test::makeSession(json, "seeds.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SeedPlacement, EveryModelRefusesASeedInsideAnObstacle) {
  for (const Model& m : kModels) {
    SCOPED_TRACE(m.name);
    // Inside the crate, and inside the wall.
    EXPECT_EQ(openError(scene(m.keys, "[1.5, 0.2, 1]", "[0, 1, 0]")),
              "seeds.json:/plants/0/position: seed position (1.5, 0.2, 1) lies inside an obstacle");
    EXPECT_EQ(openError(scene(m.keys, "[0.3, 0.5, 0]", "[0, 1, 0]")),
              "seeds.json:/plants/0/position: seed position (0.3, 0.5, 0) lies inside an obstacle");
    // On the ground at the wall's foot, growing up into the wall: the nearest surface point is
    // a tie between the ground's top and the wall's base, but the growth starts in the wall.
    EXPECT_EQ(openError(scene(m.keys, "[0.3, 0, 0]", "[0, 1, 0]")),
              "seeds.json:/plants/0/position: seed position (0.3, 0, 0) lies inside an obstacle");
    // On the ground in front of the wall, on the wall's face growing away from it, on the
    // crate's top: the plant starts.
    EXPECT_EQ(openError(scene(m.keys, "[0.3, 0, 0.3]", "[0, 1, 0]")), "");
    EXPECT_EQ(openError(scene(m.keys, "[0.3, 0.8, 0.1]", "[0, 0, 1]")), "");
    EXPECT_EQ(openError(scene(m.keys, "[1.5, 0.4, 1]", "[0, 1, 0]")), "");
  }
}

TEST(SeedPlacement, PlantsSeededWhileGrowingFollowTheSameRule) {
  for (const Model& m : kModels) {
    SCOPED_TRACE(m.name);
    auto session = test::makeSession(scene(m.keys, "[-0.5, 0, 0.5]", "[0, 1, 0]"), "seeds.json");
    Json plant = parseJson("{\"name\": \"q\", " + m.keys + R"(, "position": [-0.3, 0, 0]})", "edit");
    try {
      session->addPlant(plant, "edit");
      ADD_FAILURE() << "a seed at the wall's foot was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), "edit:/position: seed position (-0.3, 0, 0) lies inside an obstacle");
    }
    EXPECT_EQ(session->plantCount(), 1u);
    plant["position"] = {-0.3, 0, 0.3};
    EXPECT_NO_THROW(session->addPlant(plant, "edit"));
    EXPECT_EQ(session->plantCount(), 2u);
  }
}

TEST(SeedPlacement, TheRuleOnItsOwn) {
  auto session = test::makeSession(scene(kModels[0].keys, "[-0.5, 0, 0.5]", "[0, 1, 0]"));
  const env::Environment& env = session->environment();
  // A seed on the wall's face growing along it or away from it is outside; growing into it, or
  // standing a millimetre inside, is not.
  EXPECT_FALSE(env::seedInsideObstacle(env, Vec3(0.3f, 0.8f, 0.1f), Vec3(0, 1, 0)));
  EXPECT_FALSE(env::seedInsideObstacle(env, Vec3(0.3f, 0.8f, 0.1f), Vec3(0, 0, 1)));
  EXPECT_TRUE(env::seedInsideObstacle(env, Vec3(0.3f, 0.8f, 0.1f), Vec3(0, 0, -1)));
  EXPECT_TRUE(env::seedInsideObstacle(env, Vec3(0.3f, 0.8f, 0.099f), Vec3(0, 0, 1)));
  // Away from every surface nothing is asked of the direction.
  EXPECT_FALSE(env::seedInsideObstacle(env, Vec3(0.3f, 0.8f, 0.5f), Vec3(0, 0, -1)));
  EXPECT_THROW(env::checkSeedPosition(env, Vec3(0.3f, 0.0f, 0.0f), Vec3(0, 1, 0), "x"), Error);
}

}  // namespace
}  // namespace tendril

// Plants as supports (issue: ivy that climbs trees): a plant marked "support" holds climbing
// plants of the other models through the same environment queries as obstacles.
#include "session_test_util.h"
#include "support/climb_checks.h"
#include "support/determinism.h"

#include "tendril/session/edit.h"

#include "tendril/plant/plant_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace tendril::test {
namespace {

// A component-graph chestnut (seed 004) as the host, climbing ivy (seed 003) at its trunk.
std::string chestnutScene(bool support, int steps, const std::string& climbers) {
  return fmt::format(R"({{"tendril": 1, "seed": 3, "steps": {},
    "environment": {{"obstacles": [{{"name": "ground", "type": "plane", "size": [14, 14]}}],
                    "lights": [{{"type": "directional", "direction": [-0.3, -1, -0.4]}}]}},
    "plants": [{{"name": "chestnut", "model": "graph", "graph": "examples/graphs/chestnut.json",
                 "position": [0, 0, 0], "support": {}}}, {}]}})",
                     steps, support ? "true" : "false", climbers);
}

const std::string kIvyAtTrunk = R"({"name": "ivy", "species": "japanese-ivy", "position": [0.38, 0, 0], "seed": 1})";

// What a climber does on its hosts: segments through any support, segments above its first
// metre near a host stem, leaves whose upper side faces the bark.
struct OnHost {
  size_t segments = 0, crossings = 0, inside = 0;
  size_t high = 0, highOnStem = 0;
  size_t leavesOnStem = 0, leavesFacingBark = 0;
};

OnHost onHost(const plant::PlantModel& p, const env::Environment& env, float adhesion) {
  OnHost r;
  const float base = p.nodeCount() ? p.position[0].y() : 0.0f;
  for (size_t i = 0; i < p.nodeCount(); ++i) {
    const Vec3 a = p.position[i], b = p.tip(i);
    ++r.segments;
    if (env.countSegmentHits(a, b) > 0) ++r.crossings;
    if (env.exactSignedDistance(b, 1.0f) < 0.0f) ++r.inside;
    const Vec3 mid = 0.5f * (a + b);
    if (mid.y() > base + 1.0f) {
      ++r.high;
      if (auto s = env.closestPoint(mid, adhesion); s && s->onStem()) ++r.highOnStem;
    }
  }
  for (size_t l = 0; l < p.leafCount(); ++l) {
    const Vec3 attach = p.leafWorldPosition(l);
    auto s = env.closestPoint(attach, adhesion);
    if (!s || !s->onStem()) continue;
    ++r.leavesOnStem;
    const Vec3 normal = p.leafWorldRotation(l) * Vec3::UnitZ();
    if (normal.dot(s->away) > 0.0f) ++r.leavesFacingBark;
  }
  return r;
}

void print(const char* what, const OnHost& r) {
  std::printf("%s: %zu segments, %zu through a support, %zu ends inside; above 1 m %zu of %zu on a host stem; "
              "%zu of %zu leaves on a stem face away from it\n",
              what, r.segments, r.crossings, r.inside, r.highOnStem, r.high, r.leavesFacingBark, r.leavesOnStem);
}

// The climber `plant` as the queries of its system (`viewer`) see the supports, printed.
OnHost measure(session::Session& session, const plant::PlantModel& plant, uint32_t viewer, const char* what) {
  env::Environment& env = session.environment();
  env.setStemViewer(viewer);
  const OnHost r = onHost(plant, env, 0.08f);
  env.setStemViewer(env::Environment::kEveryStem);
  print(what, r);
  return r;
}

// Nothing through a support, at least `high` segments above the first metre, 90 % of them on
// a host stem, every leaf on a stem facing away from it.
void expectClimbsHost(const OnHost& r, size_t high) {
  EXPECT_EQ(r.crossings, 0u);
  EXPECT_EQ(r.inside, 0u);
  ASSERT_GT(r.high, high);
  EXPECT_GE(double(r.highOnStem), 0.9 * double(r.high)) << r.highOnStem << " of " << r.high;
  EXPECT_EQ(r.leavesFacingBark, r.leavesOnStem);
}

// A particle shoot (seed 000) grown 900 steps straight up toward an overhead light, a support,
// then climbing ivy seeded at its foot and grown 150 steps.
const std::string kShootScene = R"({"tendril": 1, "seed": 3, "steps": 900,
    "environment": {"obstacles": [{"name": "ground", "type": "plane", "size": [14, 14]}],
                    "lights": [{"type": "directional", "direction": [0, -1, 0]}]},
    "plants": [{"name": "shoot", "model": "particles", "position": [0, 0.03, 0], "seed": 1, "support": true,
                "species": {"base": "ivy-particles", "radius": 0.03, "density": 100, "phototropism": 1.0,
                            "branch_probability": 0.05, "random_walk": 0.02, "max_particles": 300}}]})";

void growShootThenIvy(session::Editor& editor) {
  editor.step(900);
  ASSERT_GT(plant::computeStats(editor.session().plants()[0]).bounds.max.y(), 2.5f);
  editor.session().addPlant(
      parseJson(R"({"name": "ivy", "species": "japanese-ivy", "position": [0.045, 0, 0], "seed": 1})", "ivy.json"),
      "ivy.json");
  editor.step(150);
}

TEST(PlantSupport, IvyClimbsAGraphChestnutAndClingsToItsStems) {
  auto session = makeSession(chestnutScene(true, 100, kIvyAtTrunk));
  session->run(100);
  const auto plants = session->plants();
  ASSERT_EQ(plants.size(), 2u);
  // The queries as the climbing plants (system 1) see them: the chestnut's stems and the ground.
  const OnHost r = measure(*session, plants[1], 1, "ivy on a graph chestnut");
  EXPECT_GT(r.segments, 800u);
  expectClimbsHost(r, 200);
  EXPECT_GT(r.leavesOnStem, 200u);
  // Above its first metre the ivy is on the tree: it climbed.
  EXPECT_GT(plant::computeStats(plants[1]).bounds.max.y(), 2.0f);
}

TEST(PlantSupport, WithoutSupportTheIvyFindsNothingToClimb) {
  // The mechanism removed: the same scene with the chestnut not a support.
  auto session = makeSession(chestnutScene(false, 100, kIvyAtTrunk));
  session->run(100);
  const auto plants = session->plants();
  EXPECT_LT(plant::computeStats(plants[1]).bounds.max.y(), 1.0f);
  EXPECT_LT(plants[1].nodeCount(), 100u);
}

TEST(PlantSupport, IvyClimbsAnLSystemTree) {
  const std::string scene = R"({"tendril": 1, "seed": 3, "steps": 120,
    "environment": {"obstacles": [{"name": "ground", "type": "plane", "size": [14, 14]}],
                    "lights": [{"type": "directional", "direction": [-0.3, -1, -0.4]}]},
    "plants": [{"name": "tree", "model": "lsystem", "grammar": "examples/grammars/abop-2.6-monopodial.ls",
                "position": [0, 0, 0], "support": true},
               {"name": "ivy", "species": "japanese-ivy", "position": [0.07, 0, 0], "seed": 1}]})";
  auto session = makeSession(scene);
  session->run(120);
  expectClimbsHost(measure(*session, session->plants()[1], 1, "ivy on an L-system tree"), 30);
}

TEST(PlantSupport, IvyClimbsAParticlePlant) {
  // The shoot, still moving under its own physics, is the ivy's only support.
  auto session = makeSession(kShootScene);
  session::Editor editor(*session);
  growShootThenIvy(editor);
  expectClimbsHost(measure(*session, session->plants()[1], 1, "ivy on a particle shoot"), 30);
}

TEST(PlantSupport, AClimberSeededWhereAClickHitsTheTrunkClimbsIt) {
  // The studio's seed tool: the ray under the cursor hits the chestnut's trunk (a stem, not an
  // obstacle), and a climbing plant seeded there along the bark's normal climbs the tree.
  auto session = makeSession(chestnutScene(true, 100, R"({"name": "moss", "model": "graph",
      "graph": "examples/graphs/fig2.json", "position": [5, 0, 5]})"));
  session::Editor editor(*session);
  // The supports are in the environment from the start, before any step.
  auto hit = session::pickSurface(*session, Vec3(3, 1.0f, 0.05f), Vec3(-1, 0, 0));
  ASSERT_TRUE(hit);
  ASSERT_TRUE(hit->onStem());
  EXPECT_EQ(session->environment().stem(hit->stem()).plant, 0u);
  session::SeedPlant seed;
  seed.model = "climb";
  seed.position = hit->point;
  seed.normal = session::seedDirection(*session, *hit, Vec3(-1, 0, 0));
  EXPECT_GT(seed.normal.y(), 0.9f);
  editor.apply(seed);
  editor.step(100);
  const auto plants = session->plants();
  ASSERT_EQ(plants.size(), 3u);
  EXPECT_GT(plant::computeStats(plants[2]).bounds.max.y(), 2.0f);
  // The climbing system is 1 (the two graph plants share system 0).
  expectClimbsHost(measure(*session, plants[2], 1, "ivy seeded on the trunk"), 200);
}

TEST(PlantSupport, CuttingAHostBranchTakesItsClimbersAndUndoBringsBothBack) {
  auto session = makeSession(kShootScene);
  session::Editor editor(*session);
  growShootThenIvy(editor);
  const auto before = session->plants();
  const uint64_t hashBefore = plant::contentHash(before);
  // The shoot's node 1 m up: everything above it goes, and the ivy's shoots on it.
  const plant::PlantModel& shoot = before[0];
  uint32_t cut = 0;
  for (uint32_t i = 0; i < shoot.nodeCount() && !cut; ++i)
    if (shoot.parent[i] >= 0 && shoot.position[i].y() > 1.0f) cut = i;
  ASSERT_GT(cut, 0u);
  size_t ivyAbove = 0;
  for (size_t i = 0; i < before[1].nodeCount(); ++i) ivyAbove += before[1].position[i].y() > 1.2f;
  ASSERT_GT(ivyAbove, 20u);
  editor.apply(session::Cut{0, cut});
  const auto after = session->plants();
  // A particle plant's cut part falls as a detached piece.
  auto attached = [](const plant::PlantModel& m) {
    size_t n = 0;
    for (uint32_t f : m.flags) n += !(f & plant::kNodeBroken);
    return n;
  };
  EXPECT_LT(attached(after[0]), attached(before[0]));
  size_t ivyAboveAfter = 0;
  for (size_t i = 0; i < after[1].nodeCount(); ++i) ivyAboveAfter += after[1].position[i].y() > 1.2f;
  std::printf("cut the shoot at node %u (%.2f m): shoot %zu -> %zu attached nodes, ivy %zu -> %zu nodes (%zu -> %zu above 1.2 m)\n",
              cut, shoot.position[cut].y(), attached(before[0]), attached(after[0]), before[1].nodeCount(),
              after[1].nodeCount(), ivyAbove, ivyAboveAfter);
  EXPECT_EQ(ivyAboveAfter, 0u);
  EXPECT_GT(after[1].nodeCount(), 20u);  // the ivy below the cut stays
  // Before any step, what the ivy clings to (what the studio's sway and the clips carry it by)
  // is the shoot as cut: every clinging node holds to a host node still on the plant, beside it.
  auto clinging = [&](const std::vector<plant::PlantModel>& plants) {
    const std::vector<session::Session::Attachment> at = session->attachments(1, plants[1], 0.08f);
    size_t held = 0, wrong = 0;
    for (size_t i = 0; i < at.size(); ++i) {
      if (at[i].plant < 0) continue;
      ++held;
      const plant::PlantModel& host = plants[size_t(at[i].plant)];
      const size_t h = size_t(at[i].node);
      if (at[i].plant != 0 || h >= host.nodeCount() || (host.flags[h] & plant::kNodeBroken)) {
        ++wrong;
        continue;
      }
      const Vec3 a = host.position[h], b = host.tip(h), p = plants[1].position[i];
      const float s = std::clamp((p - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-12f), 0.0f, 1.0f);
      wrong += (p - (a + s * (b - a))).norm() > host.radius[h] + 0.08f + 1e-3f;
    }
    return std::pair{held, wrong};
  };
  const auto [heldAfter, wrongAfter] = clinging(after);
  std::printf("after the cut, before a step: %zu ivy nodes cling, %zu of them to a node the cut took or not beside them\n",
              heldAfter, wrongAfter);
  EXPECT_GT(heldAfter, 10u);
  EXPECT_EQ(wrongAfter, 0u);
  editor.undo();
  EXPECT_EQ(plant::contentHash(session->plants()), hashBefore);
  const auto [heldUndone, wrongUndone] = clinging(session->plants());
  EXPECT_GT(heldUndone, heldAfter) << "undone, the ivy above the cut clings again";
  EXPECT_EQ(wrongUndone, 0u);
}

TEST(PlantSupport, ParticleIvyAndAnLSystemVineClimbTreesToo) {
  // Climbers of the other two models: particle ivy (seed 000) at the chestnut's trunk, and the
  // built-in ivy grammar, whose ?E probes see the stems, at a graph pine's trunk.
  auto session = makeSession(chestnutScene(true, 700, R"(
      {"name": "particle-ivy", "model": "particles", "species": "ivy-particles", "position": [0.345, 0.03, 0], "seed": 1},
      {"name": "pine", "model": "graph", "graph": "examples/graphs/pine.json", "position": [6, 0, 0], "support": true},
      {"name": "vine", "model": "lsystem", "grammar": "japanese-ivy", "derivation_length": 150,
       "position": [6.2, 0, 0], "seed": 2})"));
  session->run(700);
  const auto plants = session->plants();
  ASSERT_EQ(plants.size(), 4u);
  // Systems: graph 0 (both trees), particles 1, lsystem 2.
  const OnHost particles = measure(*session, plants[1], 1, "particle ivy on a graph chestnut");
  EXPECT_GT(plant::computeStats(plants[1]).bounds.max.y(), 1.5f);
  EXPECT_EQ(particles.crossings, 0u);
  EXPECT_EQ(particles.inside, 0u);
  ASSERT_GT(particles.high, 50u);
  EXPECT_GE(double(particles.highOnStem), 0.9 * double(particles.high));
  const OnHost vine = measure(*session, plants[3], 2, "L-system vine on a graph pine");
  EXPECT_GT(plant::computeStats(plants[3]).bounds.max.y(), 2.0f);
  expectClimbsHost(vine, 200);
}

TEST(PlantSupport, TheSameAtEveryThreadCount) {
  sameAtEveryThreadCount([&] {
    auto session = makeSession(chestnutScene(true, 40, kIvyAtTrunk));
    session->run(40);
    return plant::contentHash(session->plants());
  });
}

}  // namespace
}  // namespace tendril::test

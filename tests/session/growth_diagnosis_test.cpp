// A plant that stops in its first steps or stays far below its species' size says why
// (models/diagnosis.h): each cause — a seed under an obstacle, no support in reach, no light,
// crowding, a cap — gives its message naming the plant, once, and healthy plants of every
// model give none.
#include "session/session_test_util.h"

#include "tendril/core/log.h"
#include "tendril/models/diagnosis.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

// A ground plane (and `obstacles`, JSON text starting with a comma), one light and `plants`.
std::string groundScene(const std::string& obstacles, const std::string& plants,
                        const std::string& lightDirection = "[0.3, -1, -0.4]") {
  return R"({"tendril": 1, "seed": 7, "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [4, 4]})" +
         obstacles + R"(], "lights": [{"type": "directional", "direction": )" + lightDirection + R"(}]},
      "plants": [)" + plants + "]}";
}

const std::string kSlab = R"(, {"name": "car", "type": "box", "size": [1, 0.1, 1], "position": [0, 0.1, 0]})";
const std::string kRoof = R"(, {"name": "roof", "type": "box", "size": [4, 0.1, 4], "position": [0, 1.2, 0]})";

struct Grown {
  std::vector<session::Session::GrowthReport> problems;
  std::vector<std::string> warnings;  // what the run wrote
};

Grown grow(const std::string& json, uint32_t steps) {
  Grown g;
  log::ThreadCapture capture(&g.warnings);
  auto s = test::makeSession(json);
  s->run(steps);
  g.problems = s->diagnoseGrowth();
  return g;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The one problem found, its cause and message; fails unless exactly one was found.
void expectOne(const Grown& g, models::GrowthCause cause, const std::string& plant, const std::string& phrase,
               bool stopped) {
  ASSERT_EQ(g.problems.size(), 1u);
  const models::GrowthProblem& p = g.problems[0].problem;
  EXPECT_EQ(p.cause, cause) << models::causeName(p.cause) << ": " << p.message;
  EXPECT_EQ(p.stopped, stopped);
  EXPECT_TRUE(p.message.starts_with("plant \"" + plant + "\" ")) << p.message;
  EXPECT_TRUE(contains(p.message, phrase)) << p.message;
  EXPECT_EQ(p.message.find('\n'), std::string::npos);
  EXPECT_TRUE(!p.why.empty() && p.message.ends_with(": " + p.why)) << p.why;
}

TEST(GrowthDiagnosis, HealthyPlantsOfEveryModelGiveNone) {
  // Climbing ivy, particle ivy and an L-system ivy by the wall, an ABOP plant and a graph plant.
  const std::string plants = test::kClimbPlant + ", " + test::kParticlePlant + ", " + test::kLSystemPlant + ", " +
                             test::kGraphPlant + R"(, {"name": "ivy-l", "model": "lsystem", "grammar": "japanese-ivy",
                             "position": [-0.4, 0, 0.04]})";
  const Grown g = grow(test::sessionScene(plants), 250);
  for (const auto& r : g.problems) ADD_FAILURE() << r.problem.message;
  for (const std::string& w : g.warnings) ADD_FAILURE() << w;
  // The example scenes of the pinned results, too.
  for (const char* scene : {"default.json", "ivy-lsystem.json"}) {
    SCOPED_TRACE(scene);
    std::vector<std::string> warnings;
    log::ThreadCapture capture(&warnings);
    auto s = session::Session::open(test::sourceDir() / "examples/scenes" / scene);
    s->run(200);
    EXPECT_TRUE(s->diagnoseGrowth().empty());
    EXPECT_TRUE(warnings.empty()) << warnings.front();
  }
}

TEST(GrowthDiagnosis, ASeedUnderAnObstacleSaysSo) {
  // Particle ivy on the ground under a car-like slab: its first apex meets the slab 5 cm up
  // and grows on in its shade at a crawl.
  const Grown g = grow(groundScene(kSlab, R"({"name": "under", "model": "particles", "species": "ivy-particles",
                                              "position": [0, 0, 0]})"),
                       400);
  expectOne(g, models::GrowthCause::SeedBlocked, "under", "seed under an obstacle: its growth direction meets a surface 0.05 m",
            false);
  // The same seed beside the slab grows.
  EXPECT_TRUE(grow(groundScene(kSlab, R"({"name": "beside", "model": "particles", "species": "ivy-particles",
                                         "position": [1.5, 0, 0]})"),
                   400)
                  .problems.empty());
}

TEST(GrowthDiagnosis, NoSupportInReachSaysSo) {
  // Climbing ivy and L-system ivy on open ground: nothing to climb; the climbing model records
  // why its shoots died, the grammar's stop is judged from the scene.
  const Grown climb = grow(groundScene("", R"({"name": "lost", "model": "climb", "position": [0, 0, 0]})"), 120);
  expectOne(climb, models::GrowthCause::NoSupport, "lost", "no support in reach", true);
  EXPECT_TRUE(contains(climb.problems[0].problem.message, "where its species grows 0.80 m of stem unhindered in 30 steps"))
      << climb.problems[0].problem.message;
  const Grown lsystem =
      grow(groundScene("", R"({"name": "lost", "model": "lsystem", "grammar": "japanese-ivy", "position": [0, 0, 0]})"),
           120);
  expectOne(lsystem, models::GrowthCause::NoSupport, "lost", "no support in reach: nothing to climb within 0.08 m", true);
  EXPECT_TRUE(contains(lsystem.problems[0].problem.message, "stopped growing in its first steps"));
  // Each is written once, as a warning, by the run.
  ASSERT_EQ(climb.warnings.size(), 1u);
  EXPECT_EQ(climb.warnings[0], climb.problems[0].problem.message);
}

TEST(GrowthDiagnosis, NoLightSaysSo) {
  // Particle ivy under a wide roof 1.2 m up, the sun straight above: growing at the species'
  // shade rate. Without the roof it grows.
  const std::string plant = R"({"name": "dark", "model": "particles", "species": "ivy-particles", "position": [0, 0, 0]})";
  const Grown g = grow(groundScene(kRoof, plant, "[0, -1, 0]"), 400);
  expectOne(g, models::GrowthCause::NoLight, "dark", "too little light: 0 % exposure at its shoot tips", false);
  EXPECT_TRUE(contains(g.problems[0].problem.message, "under a quarter of the 2.00 m of stem its species grows"));
  EXPECT_TRUE(grow(groundScene("", plant, "[0, -1, 0]"), 400).problems.empty());
}

TEST(GrowthDiagnosis, CrowdingSaysSo) {
  // A climbing species whose tips die where one segment end is already near: its own first
  // segment crowds its second.
  const Grown g = grow(test::sessionScene(R"({"name": "crowd", "model": "climb", "species": {"base": "japanese-ivy",
                                              "crowding_limit": 1}, "position": [0, 0, 0.1]})"),
                       120);
  expectOne(g, models::GrowthCause::Crowded, "crowd", "crowding: stems", true);
}

TEST(GrowthDiagnosis, ACapSaysSoOnce) {
  const Grown g = grow(test::sessionScene(R"({"name": "capped", "model": "climb", "species": {"base": "japanese-ivy",
                                              "max_segments": 5}, "position": [0, 0, 0.1]})"),
                       120);
  expectOne(g, models::GrowthCause::Cap, "capped", "it reached max_segments (5)", true);
  // The model's own warning is the one line written for it.
  ASSERT_EQ(g.warnings.size(), 1u);
  EXPECT_TRUE(contains(g.warnings[0], "plant \"capped\" reached max_segments (5)")) << g.warnings[0];
}

TEST(GrowthDiagnosis, ReportsEachProblemOnceAndOnlyTheStuntedPlant) {
  // A healthy ivy beside a stunted one: only the stunted one is named, and a second report
  // (another run, a studio's next check) writes nothing new.
  std::vector<std::string> warnings;
  log::ThreadCapture capture(&warnings);
  auto s = test::makeSession(test::sessionScene(
      test::kClimbPlant + R"(, {"name": "far", "model": "climb", "position": [0, 0, 1.2]})"));
  s->run(60);
  const auto found = s->diagnoseGrowth();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].plant, 1u);
  EXPECT_EQ(found[0].problem.cause, models::GrowthCause::NoSupport);
  EXPECT_EQ(warnings.size(), 1u);
  s->run(10);
  EXPECT_EQ(s->reportGrowth().size(), 1u);
  EXPECT_EQ(warnings.size(), 1u);
}

TEST(GrowthDiagnosis, ModelsRecordWhyTheirTipsEnded) {
  // The climbing model marks a dead tip's node with its cause; the particle model its crowded
  // apices (here a species whose apices stop where two other stems are near).
  auto s = test::makeSession(test::sessionScene(R"({"name": "lost", "model": "climb", "position": [0, 0, 1.2]})"));
  s->run(60);
  const plant::PlantModel m = s->plants()[0];
  size_t noSupport = 0;
  for (size_t i = 0; i < m.nodeCount(); ++i)
    if ((m.flags[i] & plant::kNodeDead) && plant::tipEnd(m.flags[i]) == plant::TipEnd::NoSupport) ++noSupport;
  EXPECT_GE(noSupport, 1u);
  EXPECT_EQ(plant::tipEnd(plant::deadEnd(0, plant::TipEnd::Crowded)), plant::TipEnd::Crowded);
  EXPECT_EQ(plant::deadEnd(plant::deadEnd(0, plant::TipEnd::Crowded), plant::TipEnd::Capped) & plant::kNodeTipEndMask,
            uint32_t(plant::TipEnd::Capped) << plant::kNodeTipEndShift);

  auto p = test::makeSession(test::sessionScene(R"({"name": "dense", "model": "particles", "species": {"base":
                                                 "ivy-particles", "crowding": 1}, "position": [0.1, 0, 0.1]})"));
  p->run(600);
  const plant::PlantModel pm = p->plants()[0];
  size_t crowded = 0;
  for (size_t i = 0; i < pm.nodeCount(); ++i)
    if ((pm.flags[i] & plant::kNodeDead) && plant::tipEnd(pm.flags[i]) == plant::TipEnd::Crowded) ++crowded;
  EXPECT_GE(crowded, 1u);
}

}  // namespace
}  // namespace tendril

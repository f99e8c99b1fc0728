// Session state: save → load → continue is bit-identical to never saving, for every model and
// for simulated air, in memory and through session files; damaged files are Errors.
#include "session/session_test_util.h"
#include "tendril/core/error.h"
#include "tendril/session/edit.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

#include <fstream>

namespace tendril {
namespace {

struct ModelCase {
  const char* name;
  std::string plants;
  std::string wind;
};

class SessionStateTest : public ::testing::TestWithParam<ModelCase> {};

TEST_P(SessionStateTest, SaveLoadContinueIsBitIdentical) {
  const ModelCase& c = GetParam();
  const std::string json = test::sessionScene(c.plants, c.wind);
  constexpr uint32_t kBefore = 12, kAfter = 10;

  // Never saved.
  auto straight = test::makeSession(json);
  for (uint32_t i = 0; i < kBefore + kAfter; ++i) straight->step();
  EXPECT_GT(straight->segmentCount(), 5u) << c.name;  // something grew (or stands)

  // Saved in memory after kBefore steps, restored into a fresh session, continued.
  auto a = test::makeSession(json);
  for (uint32_t i = 0; i < kBefore; ++i) a->step();
  const std::vector<uint8_t> state = a->saveState();
  auto b = test::makeSession(json);
  b->loadState(state);
  EXPECT_EQ(b->stateHash(), a->stateHash());
  for (uint32_t i = 0; i < kAfter; ++i) b->step();
  EXPECT_EQ(b->stepCount(), kBefore + kAfter);
  EXPECT_EQ(b->stateHash(), straight->stateHash()) << c.name;
  EXPECT_EQ(plant::contentHash(b->plants()), plant::contentHash(straight->plants()));

  // Through a session file.
  auto dir = test::scratchDir();
  session::saveSession(dir / "s.tses", *a);
  session::LoadedSession loaded = session::loadSession(dir / "s.tses");
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());
  for (uint32_t i = 0; i < kAfter; ++i) loaded.session->step();
  EXPECT_EQ(loaded.session->stateHash(), straight->stateHash()) << c.name;

  // The restored session saves the same bytes it was given.
  auto c2 = test::makeSession(json);
  c2->loadState(state);
  EXPECT_EQ(c2->saveState(), state);
}

INSTANTIATE_TEST_SUITE_P(Models, SessionStateTest,
                         ::testing::Values(ModelCase{"climb", test::kClimbPlant, ""},
                                           ModelCase{"particles", test::kParticlePlant, ""},
                                           ModelCase{"lsystem", test::kLSystemPlant, ""},
                                           ModelCase{"graph", test::kGraphPlant, ""},
                                           ModelCase{"sph", test::kParticlePlant, test::kSphWind},
                                           ModelCase{"sphPositionBased", test::kParticlePlant, test::kSphWindPositionBased},
                                           ModelCase{"all", test::kClimbPlant + "," + test::kParticlePlant + "," +
                                                                test::kLSystemPlant + "," + test::kGraphPlant,
                                                     ""}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(SessionState, PlantsAddedAtRunTimeAreSavedAndRestored) {
  const std::string json = test::sessionScene(test::kParticlePlant);
  auto a = test::makeSession(json);
  session::Editor editor(*a);
  for (int i = 0; i < 5; ++i) editor.step();
  session::SeedPlant climb;
  climb.model = "climb";
  climb.position = Vec3(0.4f, 0, 0.1f);
  editor.apply(climb);
  editor.step(5);
  auto dir = test::scratchDir();
  session::saveSession(dir / "s.tses", *a, editor.journal());
  editor.step(8);
  session::LoadedSession loaded = session::loadSession(dir / "s.tses");
  ASSERT_EQ(loaded.session->plantCount(), 2u);
  ASSERT_EQ(loaded.journal.size(), 3u);  // 5 steps, the seed, 5 steps (the 8 after saving are not in it)
  EXPECT_EQ(std::get<session::Step>(loaded.journal[2].edit).count, 5u);
  for (int i = 0; i < 8; ++i) loaded.session->step();
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());
}

TEST(SessionState, DamagedSessionFilesAreErrorsNotCrashes) {
  auto dir = test::scratchDir();
  auto a = test::makeSession(test::sessionScene(test::kClimbPlant + "," + test::kParticlePlant));
  for (int i = 0; i < 15; ++i) a->step();
  session::saveSession(dir / "good.tses", *a);
  const std::string good = test::readText(dir / "good.tses");

  auto errorOf = [&](const std::string& bytes) -> std::string {
    test::writeText(dir / "bad.tses", bytes);
    try {
      session::loadSession(dir / "bad.tses");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  // Truncated anywhere: an Error naming the file, on one line.
  for (size_t cut = 0; cut < good.size(); cut += std::max<size_t>(1, good.size() / 47)) {
    std::string what = errorOf(good.substr(0, cut));
    ASSERT_FALSE(what.empty()) << "truncated at " << cut;
    EXPECT_EQ(what.rfind((dir / "bad.tses").string(), 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  // An unknown version.
  std::string future = good;
  future[4] = 99;
  EXPECT_EQ(errorOf(future), (dir / "bad.tses").string() +
                                 ":byte 4: session file version 99 is not supported (this build reads 1)");
  // Not a session file at all.
  EXPECT_NE(errorOf("{\"tendril\": 1}").find("not a Tendril session file"), std::string::npos);
  // Garbage after a valid header; flipped bytes anywhere either load or are Errors.
  EXPECT_FALSE(errorOf(good.substr(0, 8) + std::string(400, '\xff')).empty());
  for (size_t at = 8; at < good.size(); at += std::max<size_t>(1, good.size() / 31)) {
    std::string flipped = good;
    flipped[at] = char(flipped[at] ^ 0x5a);
    errorOf(flipped);
  }
  EXPECT_NE(errorOf("").find("not a Tendril session file"), std::string::npos);
  try {
    session::loadSession(dir / "missing.tses");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "missing.tses").string() + ": session file does not exist");
  }
}

// What edits may make is read back: edit scripts allow wider emitters than scenes (500 m/s, an
// 80° spread) and keep their direction as given, so the saved wind's checks must accept them.
TEST(SessionState, EmittersEditsMayMakeAreReadBack) {
  const std::string json = test::sessionScene(test::kClimbPlant);
  auto a = test::makeSession(json);
  session::Editor editor(*a);
  editor.step(2);
  session::AddEmitter add;
  add.emitter.position = Vec3(0.1f, 0.5f, 0.2f);
  add.emitter.direction = Vec3(2.0f, 0.0f, 0.5f);
  add.emitter.speed = 500.0f;
  add.emitter.radius = 400.0f;
  add.emitter.reach = 1e5f;
  add.emitter.spread = radians(80.0f);
  add.emitter.rate = 1e8f;
  editor.apply(add);
  editor.step(2);
  const std::vector<uint8_t> state = a->saveState();
  auto b = test::makeSession(json);
  EXPECT_NO_THROW(b->loadState(state));
  EXPECT_EQ(b->saveState(), state);
}

// Sessions the session fuzzer (fuzz/README.md) damaged in ways the reader missed: a particle
// world whose saved spatial hash points past its entries (a heap overflow in the next step's
// crowding query), air with a finite speed of 1e37 m/s (NaN positions in the next step), a
// painted stroke 10²⁵ m away and a climbing plant's node 3·10³² m away (overflowing cell
// indices).
TEST(SessionState, DamagedStatesFoundByFuzzingAreErrors) {
  const struct {
    const char* file;
    const char* message;
  } cases[] = {{"fuzz-world-hash.tses", "the spatial hash of the saved world is damaged"},
               {"fuzz-air-speed.tses", "the saved air's particle 122 is damaged"},
               {"fuzz-stroke-far.tses", "a painted stroke of the saved environment is out of range"},
               {"fuzz-climb-far.tses", "a node of a saved climbing plant ends out of range"}};
  for (const auto& c : cases) {
    const std::filesystem::path path = test::sourceDir() / "tests/session/data" / c.file;
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    try {
      session::loadSession(path);
      ADD_FAILURE() << c.file << " loaded";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path.string() + ":byte ", 0), 0u) << what;
      EXPECT_NE(what.find(c.message), std::string::npos) << what;
    }
  }
}

TEST(SessionState, WritesAreCrashSafe) {
  auto dir = test::scratchDir();
  auto a = test::makeSession(test::sessionScene(test::kClimbPlant));
  session::saveSession(dir / "s.tses", *a);
  const std::string before = test::readText(dir / "s.tses");
  // A session built without its scene document cannot be saved; the file stays as it was.
  scene::Scene s = scene::parseScene(parseJson(test::sessionScene(test::kClimbPlant), "x"), "x", test::sourceDir());
  session::Session bare(std::move(s));
  EXPECT_THROW(session::saveSession(dir / "s.tses", bare), Error);
  EXPECT_EQ(test::readText(dir / "s.tses"), before);
  EXPECT_THROW(session::saveSession(dir / "no-such-dir/s.tses", *a), Error);
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().filename(), "s.tses") << "left behind: " << e.path();
}

}  // namespace
}  // namespace tendril

// Edits with undo/redo: every edit changes what a user would see, undo restores the exact
// previous state (hash of every plant and the environment), redo brings the edit back.
#include "session/session_test_util.h"
#include "support/particle_session.h"
#include "tendril/core/error.h"
#include "tendril/particles/world.h"
#include "tendril/session/edit.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

using namespace session;

// A grown branch particle of plant 0 (a particle plant): the one farthest from the root.
uint32_t grownParticle(const Session& s) {
  const particles::ParticleWorld& w = *test::particleWorld(s);
  uint32_t best = particles::kNone;
  for (uint32_t i = 0; i < w.capacity(); ++i) {
    const uint32_t f = w.flags(i);
    if ((f & particles::kActive) && (f & particles::kGrown) &&
        !(f & (particles::kLeaf | particles::kDetached | particles::kRoot)) && w.plantOf(i) == 0)
      best = i;
  }
  return best;
}

struct EditFixture : ::testing::Test {
  void SetUp() override {
    session = test::makeSession(test::sessionScene(test::kParticlePlant + "," + test::kClimbPlant));
    editor = std::make_unique<Editor>(*session);
    editor->step(60);
  }
  // Applies the edit, checks that it changed the state, that undo restores the exact previous
  // state (and stepping on from it matches stepping on from the saved bytes) and that redo
  // brings the edited state back.
  void checkUndoRedo(const Edit& edit, bool changes = true) {
    const uint64_t before = session->stateHash();
    const std::vector<uint8_t> bytes = session->saveState();
    editor->apply(edit);
    const uint64_t after = session->stateHash();
    if (changes) {
      EXPECT_NE(after, before) << editName(edit);
    }
    ASSERT_TRUE(editor->canUndo());
    editor->undo();
    EXPECT_EQ(session->stateHash(), before) << editName(edit);
    EXPECT_EQ(session->saveState(), bytes) << editName(edit);
    ASSERT_TRUE(editor->canRedo());
    editor->redo();
    EXPECT_EQ(session->stateHash(), after) << editName(edit);
    editor->undo();
    // Stepping on after an undo is stepping on from the state before the edit.
    auto reference = test::makeSession(test::sessionScene(test::kParticlePlant + "," + test::kClimbPlant));
    reference->loadState(bytes);
    for (int i = 0; i < 3; ++i) reference->step(), session->step();
    EXPECT_EQ(session->stateHash(), reference->stateHash()) << editName(edit);
  }
  std::unique_ptr<Session> session;
  std::unique_ptr<Editor> editor;
};

TEST_F(EditFixture, SeedPlantOfEveryModel) {
  const std::pair<const char*, const char*> models[] = {{"particles", ""},
                                                        {"climb", "clematis"},
                                                        {"lsystem", "examples/grammars/abop-1.24b.ls"},
                                                        {"graph", "examples/graphs/fig2.json"}};
  for (const auto& [model, species] : models) {
    SeedPlant e;
    e.model = model;
    e.species = species;
    e.position = Vec3(0.6f, 0.0f, 0.3f);
    e.normal = Vec3::UnitY();
    e.seed = 5;
    const size_t n = session->plantCount();
    editor->apply(e);
    ASSERT_EQ(session->plantCount(), n + 1) << model;
    EXPECT_EQ(session->plantSpec(n).model, model);
    editor->step(2);
    EXPECT_GT(session->plants()[n].nodeCount(), 0u) << model;
    editor->undo();
    EXPECT_EQ(session->plantCount(), n) << model;
  }
  SeedPlant e;
  e.model = "particles";
  e.position = Vec3(0.6f, 0.0f, 0.3f);
  checkUndoRedo(e);
}

TEST_F(EditFixture, SeedPlantErrorsLeaveTheSessionAsItWas) {
  const uint64_t before = session->stateHash();
  SeedPlant inside;
  inside.model = "climb";
  inside.position = Vec3(0, -0.1f, 0.5f);  // inside the ground slab
  SeedPlant unknown;
  unknown.model = "particles";
  unknown.species = "no-such-species";
  SeedPlant grammarless;
  grammarless.model = "lsystem";
  for (const SeedPlant& e : {inside, unknown, grammarless}) {
    try {
      editor->apply(e);
      ADD_FAILURE() << "no error for " << e.model << " " << e.species;
    } catch (const Error& err) {
      EXPECT_EQ(std::string(err.what()).find('\n'), std::string::npos);
      EXPECT_EQ(err.source(), "seed_plant") << err.what();
    }
    EXPECT_EQ(session->stateHash(), before);
  }
  EXPECT_EQ(editor->undoDepth(), 0u);
}

TEST_F(EditFixture, SeedBranchOnAGrownParticle) {
  const uint32_t p = grownParticle(*session);
  ASSERT_NE(p, particles::kNone);
  checkUndoRedo(SeedBranch{0, p, Vec3(1, 0.5f, 0)});
  const size_t before = test::particleWorld(*session)->particleCount();
  editor->apply(SeedBranch{0, p, Vec3(1, 0.5f, 0)});
  EXPECT_EQ(test::particleWorld(*session)->particleCount(), before + 1);
  EXPECT_THROW(editor->apply(SeedBranch{1, p, Vec3::UnitX()}), Error);  // plant 1 is a climbing plant
  EXPECT_THROW(editor->apply(SeedBranch{0, 1u << 30, Vec3::UnitX()}), Error);
}

TEST_F(EditFixture, CutParticleAndClimbingPlants) {
  const size_t particleNodes = session->plants()[0].nodeCount();
  ASSERT_GT(particleNodes, 4u);
  checkUndoRedo(Cut{0, uint32_t(particleNodes / 2)});
  const size_t climbNodes = session->plants()[1].nodeCount();
  ASSERT_GT(climbNodes, 4u);
  checkUndoRedo(Cut{1, uint32_t(climbNodes / 2)});
  editor->apply(Cut{1, 2});
  EXPECT_LE(session->plants()[1].nodeCount(), 2u);  // nodes beyond the cut went
  // The cut piece of a particle plant falls: its particles come out broken.
  editor->apply(Cut{0, uint32_t(particleNodes / 2)});
  const plant::PlantModel cut = session->plants()[0];
  size_t broken = 0;
  for (uint32_t f : cut.flags) broken += (f & plant::kNodeBroken) != 0;
  EXPECT_GT(broken, 0u);
  EXPECT_THROW(editor->apply(Cut{1, 100000}), Error);
  EXPECT_THROW(editor->apply(Cut{7, 0}), Error);
}

TEST_F(EditFixture, CutByParticleIsTheCutAtTheNodeHoldingIt) {
  // A particle plant cut by handle cuts where a cut by that handle's node cuts; the journal
  // keeps the handle. Climbing plants have no handles; a handle that is not a segment is an error.
  const std::vector<uint32_t> handles = session->system(0).grip()->nodeHandles(0);
  ASSERT_GT(handles.size(), 4u);
  const uint32_t node = uint32_t(handles.size() / 2);
  const uint64_t before = session->stateHash();
  editor->apply(Cut{0, node});
  const uint64_t byNode = session->stateHash();
  editor->undo();
  ASSERT_EQ(session->stateHash(), before);
  Cut byHandle{0, 0, handles[node]};
  editor->apply(byHandle);
  EXPECT_EQ(session->stateHash(), byNode);
  EXPECT_NE(byNode, before);
  EXPECT_EQ(editToJson(byHandle).value("particle", 0u), handles[node]);
  EXPECT_FALSE(editToJson(byHandle).contains("node"));
  EXPECT_THROW(editor->apply(Cut{1, 0, 0}), Error);        // plant 1 is a climbing plant
  EXPECT_THROW(editor->apply(Cut{0, 0, 1u << 30}), Error);  // no such particle
}

TEST_F(EditFixture, DragGestureIsOneUndoEntry) {
  const uint32_t p = grownParticle(*session);
  ASSERT_NE(p, particles::kNone);
  const uint64_t before = session->stateHash();
  const size_t depth = editor->undoDepth();
  const Vec3 start = test::particleWorld(*session)->position(p);
  editor->apply(DragBegin{0, p, start + Vec3(0.05f, 0, 0.05f), 0.5f});
  EXPECT_TRUE(editor->dragging());
  editor->step(3);
  const Vec3 target = start + Vec3(0.1f, 0.05f, 0.1f);
  editor->apply(DragMove{target});
  editor->step(3);
  EXPECT_LT((test::particleWorld(*session)->position(p) - target).norm(), 0.9f * (start - target).norm())
      << "the drag pulls the particle toward its target";
  editor->apply(DragEnd{});
  EXPECT_FALSE(editor->dragging());
  EXPECT_EQ(editor->undoDepth(), depth + 1);
  editor->undo();
  EXPECT_EQ(session->stateHash(), before);
  EXPECT_FALSE(editor->dragging());
  EXPECT_THROW(editor->apply(DragMove{start}), Error);
  EXPECT_THROW(editor->apply(DragEnd{}), Error);
  checkUndoRedo(DragBegin{0, p, start + Vec3(0, 0.1f, 0), 1.0f}, false);
}

TEST_F(EditFixture, PaintStrokeNearAGrownParticleSeedsABranch) {
  const uint32_t p = grownParticle(*session);
  ASSERT_NE(p, particles::kNone);
  PaintStroke e;
  e.stroke.radius = 0.2f;
  e.stroke.points = {test::particleWorld(*session)->head(p) + Vec3(0.05f, 0, 0)};
  checkUndoRedo(e);
  const size_t before = test::particleWorld(*session)->particleCount();
  editor->apply(e);
  EXPECT_EQ(session->environment().strokes().size(), 1u);
  EXPECT_EQ(test::particleWorld(*session)->particleCount(), before + 1);
  PaintStroke repel = e;
  repel.stroke.attract = false;
  checkUndoRedo(repel);
  PaintStroke empty;
  EXPECT_THROW(editor->apply(empty), Error);
}

TEST_F(EditFixture, MoveObstacleAndLight) {
  MoveObstacle move;
  move.obstacle = 1;
  move.worldFromLocal.translation = Vec3(0, 0.05f, -0.1f);
  move.worldFromLocal.rotation = Quat(Eigen::AngleAxisf(0.2f, Vec3::UnitY()));
  checkUndoRedo(move);
  editor->apply(move);
  EXPECT_EQ(session->environment().obstacle(1).worldFromLocal.translation, move.worldFromLocal.translation);
  EXPECT_THROW(editor->apply(MoveObstacle{9, {}, std::nullopt}), Error);
  MoveLight light;
  light.light = 0;
  light.value.direction = Vec3(1, -1, 0).normalized();
  checkUndoRedo(light);
  EXPECT_THROW(editor->apply(MoveLight{3, {}}), Error);
}

TEST_F(EditFixture, WindEmitters) {
  env::WindEmitter e;
  e.position = Vec3(-1, 0.5f, 0.3f);
  e.speed = 4.0f;
  checkUndoRedo(AddEmitter{e});
  editor->apply(AddEmitter{e});
  ASSERT_EQ(session->environment().windField().settings().emitters.size(), 1u);
  EXPECT_GT(session->environment().wind(Vec3(-0.5f, 0.5f, 0.3f), 0.0f).x(), 0.5f);
  env::WindEmitter stronger = e;
  stronger.speed = 8.0f;
  checkUndoRedo(EditEmitter{0, stronger});
  checkUndoRedo(RemoveEmitter{0});
  EXPECT_THROW(editor->apply(RemoveEmitter{4}), Error);
}

TEST_F(EditFixture, LiveSpeciesOfParticlePlants) {
  SetSpecies e;
  e.plant = 0;
  e.keys = Json{{"particle_length", 0.06}};
  checkUndoRedo(e, false);
  editor->apply(e);
  EXPECT_FLOAT_EQ(test::particleWorld(*session)->species(0).particleLength, 0.06f);
  editor->step(5);
  SetSpecies typo;
  typo.plant = 0;
  typo.keys = Json{{"particle_lenght", 0.06}};
  try {
    editor->apply(typo);
    ADD_FAILURE();
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("particle_lenght"), std::string::npos) << err.what();
  }
  SetSpecies climb;
  climb.plant = 1;
  climb.keys = Json{{"segment_length", 0.05}};
  EXPECT_THROW(editor->apply(climb), Error);  // climbing plants cannot change their species while growing
}

TEST_F(EditFixture, StepsAreNotUndoEntriesAndClearRedo) {
  PaintStroke e;
  e.stroke.points = {Vec3(0.5f, 0.5f, 0)};
  const uint64_t before = session->stateHash();
  editor->apply(e);
  editor->step(4);
  editor->undo();  // back to before the stroke, steps included
  EXPECT_EQ(session->stateHash(), before);
  editor->redo();
  editor->undo();
  editor->step(1);
  EXPECT_FALSE(editor->canRedo());
  EXPECT_THROW(editor->apply(Redo{}), Error);
}

TEST_F(EditFixture, HistoryMemoryIsCapped) {
  const size_t one = session->saveState().size();
  Editor small(*session, 2 * one + one / 2);
  for (int i = 0; i < 5; ++i) {
    PaintStroke e;
    e.stroke.points = {Vec3(0.1f * float(i), 0.5f, 0)};
    small.apply(e);
  }
  EXPECT_EQ(small.undoDepth(), 2u);
  EXPECT_LE(small.historyBytes(), 2 * one + one / 2);
}

TEST(EditPick, PicksTheNearestNodeAndSurface) {
  auto s = test::makeSession(test::sessionScene(test::kParticlePlant));
  for (int i = 0; i < 40; ++i) s->step();
  const plant::PlantModel p = s->plants()[0];
  const size_t n = p.nodeCount() / 2;
  const Vec3 mid = 0.5f * (p.position[n] + p.tip(n));
  const Vec3 eye = mid + Vec3(0.3f, 0.0f, 1.0f);
  auto pick = pickNode(*s, eye, mid - eye);
  ASSERT_TRUE(pick);
  EXPECT_EQ(pick->plant, 0u);
  EXPECT_LT((pick->point - mid).norm(), 0.05f);
  ASSERT_NE(pick->particle, kNoParticle);
  EXPECT_EQ(test::particleWorld(*s)->plantOf(pick->particle), 0u);
  EXPECT_FALSE(pickNode(*s, eye, Vec3(0, 1, 0)));
  auto hit = pickSurface(*s, Vec3(1, 1, 1), Vec3(0, -1, 0));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->point.y(), 0.0f, 1e-4f);
}

}  // namespace
}  // namespace tendril

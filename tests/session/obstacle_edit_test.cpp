// Support meshes imported while plants grow (add_obstacle) and obstacles rescaled
// (move_obstacle's "scale"): undo restores the exact state, bad files change nothing, session
// files keep them, and every model treats them exactly as it treats the same mesh given in the
// scene file.
#include "session/session_test_util.h"
#include "support/run_command.h"
#include "tendril/core/archive.h"
#include "tendril/core/error.h"
#include "tendril/plant/plant_model.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

#include <fmt/format.h>

namespace tendril {
namespace {

using namespace session;
namespace fs = std::filesystem;

// The wall of test::sessionScene as a mesh file: 2 m wide, 1.5 m tall, its front face at z = 0.
fs::path writeWall(const fs::path& dir) {
  fs::path p = dir / "wall.obj";
  test::writeText(p, test::boxObj(Vec3(-1, 0, -0.1f), Vec3(1, 1.5f, 0)));
  return p;
}

// A scene with the ground only and these plants.
std::string groundScene(const std::string& plants, const std::string& extraObstacle = "") {
  return std::string(R"({"tendril": 1, "seed": 7, "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [3, 3]})") +
         (extraObstacle.empty() ? "" : ", " + extraObstacle) +
         R"(], "lights": [{"type": "directional", "direction": [0.3, -1, -0.4]}]}, "plants": [)" + plants + "]}";
}

AddObstacle importOf(const fs::path& path) {
  AddObstacle e;
  e.path = path.string();
  e.name = "imported";
  return e;
}

std::string errorOf(Editor& editor, const Edit& edit) {
  try {
    editor.apply(edit);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ObstacleEdits, ImportIsUndoneAndRedoneExactly) {
  auto dir = test::scratchDir();
  const fs::path wall = writeWall(dir);
  auto s = test::makeSession(groundScene(test::kParticlePlant + "," + test::kClimbPlant));
  Editor editor(*s);
  editor.step(20);
  const uint64_t before = s->stateHash();
  const std::vector<uint8_t> bytes = s->saveState();
  const uint64_t revision = s->obstacleRevision();

  editor.apply(importOf(wall));
  ASSERT_EQ(s->environment().obstacleCount(), 2u);
  EXPECT_EQ(s->environment().obstacle(1).name, "imported");
  EXPECT_EQ(s->environment().obstacle(1).triangles, 12u);
  EXPECT_TRUE(s->environment().obstacle(1).closed);
  EXPECT_EQ(s->obstaclePath(1), wall.string());
  EXPECT_NE(s->obstacleRevision(), revision);
  // The new obstacle answers the environment's queries at once.
  EXPECT_LT(s->environment().signedDistance(Vec3(0, 0.7f, -0.05f)), 0.0f);
  const uint64_t after = s->stateHash();
  EXPECT_NE(after, before);

  editor.undo();
  EXPECT_EQ(s->environment().obstacleCount(), 1u);
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(s->saveState(), bytes);
  EXPECT_GT(s->environment().signedDistance(Vec3(0, 0.7f, -0.05f)), 0.0f);
  editor.redo();
  EXPECT_EQ(s->environment().obstacleCount(), 2u);
  EXPECT_EQ(s->stateHash(), after);

  // Stepping on after the undo is stepping on from the state before the import.
  editor.undo();
  auto reference = test::makeSession(groundScene(test::kParticlePlant + "," + test::kClimbPlant));
  reference->loadState(bytes);
  for (int i = 0; i < 5; ++i) reference->step(), s->step();
  EXPECT_EQ(s->stateHash(), reference->stateHash());
}

TEST(ObstacleEdits, BadFilesAreOneLineErrorsNamingThemAndChangeNothing) {
  auto dir = test::scratchDir();
  test::writeText(dir / "empty.obj", "# no faces\n");
  test::writeText(dir / "broken.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n");
  auto s = test::makeSession(groundScene(test::kParticlePlant));
  Editor editor(*s);
  editor.step(5);
  const uint64_t before = s->stateHash();
  const uint64_t revision = s->obstacleRevision();
  for (const fs::path& p : {dir / "missing.obj", dir / "empty.obj", dir / "broken.stl"}) {
    const std::string message = errorOf(editor, importOf(p));
    EXPECT_NE(message.find(p.string()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(s->stateHash(), before) << p;
    EXPECT_EQ(s->environment().obstacleCount(), 1u);
    EXPECT_EQ(s->obstacleRevision(), revision);
  }
  AddObstacle flat = importOf(writeWall(dir));
  flat.scale = Vec3(1, 0, 1);
  EXPECT_EQ(errorOf(editor, flat), "add_obstacle:/scale: must be in [1e-4, 1e4] on every axis, got [1, 0, 1]");
  AddObstacle nowhere;
  EXPECT_NE(errorOf(editor, nowhere).find("add_obstacle:/path"), std::string::npos);
  EXPECT_EQ(editor.undoDepth(), 0u);
  EXPECT_EQ(s->stateHash(), before);

  // A relative path is the scene directory's (the test scenes' is the source tree).
  const std::string relative = errorOf(editor, importOf("no/such/mesh.obj"));
  EXPECT_NE(relative.find((test::sourceDir() / "no/such/mesh.obj").lexically_normal().string()), std::string::npos)
      << relative;
}

// Plants seeded after the import grow exactly as they do beside the same mesh given in the
// scene file: climbing plants climb it, particle plants collide with it and L-system queries
// see it.
TEST(ObstacleEdits, PlantsTreatAnImportedMeshAsASceneMesh) {
  auto dir = test::scratchDir();
  const fs::path wall = writeWall(dir);
  const std::string plants = test::kClimbPlant + "," +
                             R"({"name": "sprout", "model": "particles", "species": "ivy-particles",
                                 "position": [0.3, 0, 0.08], "direction": [0, 0.5, -1]})" +
                             "," + test::kLSystemPlant;
  auto inScene = test::makeSession(
      groundScene(plants, fmt::format(R"({{"name": "wall", "type": "mesh", "path": "{}"}})", wall.string())));
  auto imported = test::makeSession(groundScene(""));
  Editor editor(*imported);
  editor.apply(importOf(wall));
  const Json plantList = parseJson("[" + plants + "]", "plants");
  for (const Json& p : plantList) imported->addPlant(p, "test");
  for (int i = 0; i < 60; ++i) inScene->step(), imported->step();

  const std::vector<plant::PlantModel> a = inScene->plants(), b = imported->plants();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(plant::contentHash(a[i]), plant::contentHash(b[i])) << a[i].name;

  // The climbing plant went up the wall and stayed on its face; no particle of the particle
  // plant, which grew toward the wall, is inside it.
  const plant::PlantModel& ivy = b[0];
  float top = 0.0f;
  for (size_t n = 0; n < ivy.nodeCount(); ++n) {
    top = std::max(top, ivy.tip(n).y());
    EXPECT_GT(imported->environment().signedDistance(ivy.tip(n)), -0.01f) << "node " << n << " went into the wall";
  }
  EXPECT_GT(top, 0.25f) << "the ivy should climb the imported wall";
  const plant::PlantModel& sprout = b[1];
  ASSERT_GT(sprout.nodeCount(), 3u);
  for (size_t n = 0; n < sprout.nodeCount(); ++n)
    EXPECT_GT(imported->environment().signedDistance(sprout.position[n]), -0.01f) << "particle node " << n;
}

TEST(ObstacleEdits, ScaleIsUndoneExactlyAndMatchesASceneScale) {
  auto dir = test::scratchDir();
  const fs::path wall = writeWall(dir);
  const std::string scaled = fmt::format(R"({{"name": "wall", "type": "mesh", "path": "{}", "scale": [1.5, 0.4, 1]}})",
                                         wall.string());
  auto inScene = test::makeSession(groundScene(test::kClimbPlant, scaled));
  auto s = test::makeSession(groundScene(test::kClimbPlant));
  Editor editor(*s);
  editor.apply(importOf(wall));
  const uint64_t before = s->stateHash();
  const Bounds3 bounds = s->environment().obstacle(1).worldBounds;
  MoveObstacle move;
  move.obstacle = 1;
  move.scale = Vec3(1.5f, 0.4f, 1.0f);
  editor.apply(move);
  EXPECT_EQ(s->obstacleScale(1), Vec3(1.5f, 0.4f, 1.0f));
  EXPECT_NEAR(s->environment().obstacle(1).worldBounds.max.y(), 0.6f, 1e-5f);
  EXPECT_NEAR(s->environment().obstacle(1).worldBounds.max.x(), 1.5f, 1e-5f);
  // The climbing plant grows as it does beside the mesh scaled in the scene file.
  const uint64_t scaledHash = s->stateHash();
  for (int i = 0; i < 30; ++i) inScene->step(), s->step();
  EXPECT_EQ(plant::contentHash(s->plants()[0]), plant::contentHash(inScene->plants()[0]));
  EXPECT_NE(s->stateHash(), scaledHash);  // it grew

  auto t = test::makeSession(groundScene(test::kClimbPlant));
  Editor e2(*t);
  e2.apply(importOf(wall));
  EXPECT_EQ(t->stateHash(), before);
  // (the bytes of another session may differ in struct padding; this session's may not)
  const std::vector<uint8_t> tBytes = t->saveState();
  e2.apply(move);
  EXPECT_EQ(t->stateHash(), scaledHash);
  e2.undo();
  EXPECT_EQ(t->stateHash(), before);
  EXPECT_EQ(t->saveState(), tBytes);
  EXPECT_EQ(t->obstacleScale(1), Vec3::Ones());
  EXPECT_TRUE(t->environment().obstacle(1).worldBounds.max.isApprox(bounds.max));
  // A scene obstacle scales too (the ground: non-uniform).
  MoveObstacle ground;
  ground.obstacle = 0;
  ground.scale = Vec3(0.5f, 1.0f, 2.0f);
  e2.apply(ground);
  EXPECT_NEAR(t->environment().obstacle(0).worldBounds.max.z(), 3.0f, 1e-5f);
  e2.undo();
  EXPECT_EQ(t->stateHash(), before);

  MoveObstacle bad = move;
  bad.scale = Vec3(-1, 1, 1);
  EXPECT_THROW(e2.apply(bad), Error);
  EXPECT_EQ(t->stateHash(), before);
}

TEST(ObstacleEdits, SessionFilesKeepImportedAndScaledObstacles) {
  auto dir = test::scratchDir();
  const fs::path wall = writeWall(dir);
  const std::string json = groundScene(test::kParticlePlant);
  auto a = test::makeSession(json);
  Editor editor(*a);
  editor.step(4);
  editor.apply(importOf(wall));
  MoveObstacle move;
  move.obstacle = 1;
  move.worldFromLocal.translation = Vec3(0.1f, 0, 0);
  move.scale = Vec3::Constant(0.8f);
  editor.apply(move);
  editor.step(4);
  saveSession(dir / "s.tses", *a, editor.journal());
  LoadedSession loaded = loadSession(dir / "s.tses");
  ASSERT_EQ(loaded.session->environment().obstacleCount(), 2u);
  EXPECT_EQ(loaded.session->obstacleScale(1), Vec3::Constant(0.8f));
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());
  for (int i = 0; i < 6; ++i) loaded.session->step(), a->step();
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());

  // The journal replays the import and the scale on a fresh session of the scene.
  auto replayed = test::makeSession(json);
  Editor replayEditor(*replayed);
  EditScript script{"journal", loaded.journal};
  runEditScript(replayEditor, script);
  for (int i = 0; i < 6; ++i) replayed->step();
  EXPECT_EQ(replayed->stateHash(), a->stateHash());

  // The mesh file gone: loading names it.
  fs::remove(wall);
  try {
    loadSession(dir / "s.tses");
    ADD_FAILURE() << "no error without the mesh file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(wall.string()), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

// A climbing ivy seeded on a box's side goes with the box when it moves: every node, and its
// tips, by the box's motion; it grows on over the moved box without passing through it. Undo
// puts both back.
TEST(ObstacleEdits, AClimberSeededOnAMovedBoxGoesWithIt) {
  auto s = test::makeSession(groundScene(
      R"({"name": "ivy", "species": "japanese-ivy", "position": [0, 0.1, 0.312], "seed": 2})",
      R"({"name": "box", "type": "box", "size": [0.6, 0.5, 0.6], "position": [0, 0.25, 0]})"));
  Editor editor(*s);
  editor.step(30);
  const plant::PlantModel before = s->plants()[0];
  ASSERT_GT(before.nodeCount(), 20u);
  const uint64_t hashBefore = s->stateHash();
  MoveObstacle move{1, {}, std::nullopt};
  move.worldFromLocal.rotation = Quat(Eigen::AngleAxisf(0.6f, Vec3::UnitY()));
  move.worldFromLocal.translation = Vec3(0.9f, 0.25f, -0.3f);
  const RigidTransform motion = move.worldFromLocal * s->environment().obstacle(1).worldFromLocal.inverse();
  editor.apply(move);
  const plant::PlantModel after = s->plants()[0];
  ASSERT_EQ(after.nodeCount(), before.nodeCount());
  float worst = 0.0f;
  for (size_t i = 0; i < after.nodeCount(); ++i)
    worst = std::max(worst, (after.position[i] - motion.applyPoint(before.position[i])).norm());
  EXPECT_LT(worst, 1e-4f) << "every node moved with the box";
  editor.step(20);
  const plant::PlantModel grown = s->plants()[0];
  EXPECT_GT(grown.nodeCount(), after.nodeCount()) << "it grows on";
  size_t crossing = 0, far = 0;
  for (size_t i = 0; i < grown.nodeCount(); ++i) {
    crossing += s->environment().countSegmentHits(grown.position[i], grown.tip(i)) > 0;
    const auto sp = s->environment().closestPoint(grown.tip(i), 0.08f);
    far += !sp;
  }
  std::printf("ivy on a moved box: %zu nodes moved (farthest %.2g m off the box's motion), %zu after 20 more "
              "steps, %zu segments through a surface, %zu ends farther than 8 cm from any surface\n",
              after.nodeCount(), worst, grown.nodeCount(), crossing, far);
  EXPECT_EQ(crossing, 0u);
  EXPECT_LT(far, grown.nodeCount() / 10) << "it still climbs the box";
  editor.undo();  // the steps after the move are not an undo entry: this undoes the move
  EXPECT_EQ(s->stateHash(), hashBefore);
}

TEST(ObstacleEdits, JsonFormsRoundTripAndAreChecked) {
  const char* script = R"({"tendril_edits": 1, "edits": [
    {"at_step": 0, "edit": "add_obstacle", "path": "meshes/post.obj", "name": "post", "translation": [0.5, 0, 0],
     "rotation": [1, 0, 0, 0], "scale": [1, 2, 1], "color": [0.5, 0.4, 0.3]},
    {"at_step": 0, "edit": "add_obstacle", "path": "post.glb"},
    {"at_step": 2, "edit": "move_obstacle", "obstacle": 1, "translation": [0, 0, 0], "scale": 2},
    {"at_step": 2, "edit": "move_obstacle", "obstacle": 1, "scale": [1, 0.5, 2]}
  ]})";
  const EditScript parsed = parseEditScript(parseJson(script, "edits.json"), "edits.json");
  ASSERT_EQ(parsed.edits.size(), 4u);
  const auto& first = std::get<AddObstacle>(parsed.edits[0].edit);
  EXPECT_EQ(first.path, "meshes/post.obj");
  EXPECT_EQ(first.scale, Vec3(1, 2, 1));
  EXPECT_EQ(std::get<AddObstacle>(parsed.edits[1].edit).scale, Vec3::Ones());
  EXPECT_EQ(std::get<MoveObstacle>(parsed.edits[2].edit).scale, Vec3::Constant(2));
  for (const TimedEdit& t : parsed.edits) {
    Json j = editToJson(t.edit);
    JsonObject o(j, "edit");
    Edit back = readEdit(o);
    o.finish();
    EXPECT_EQ(editToJson(back), j);
  }
  // A move without "scale" keeps the obstacle's scale (and is written without one).
  Json plain = editToJson(MoveObstacle{1, {}, std::nullopt});
  EXPECT_FALSE(plain.contains("scale"));

  auto error = [](const std::string& edit) {
    try {
      parseEditScript(parseJson(R"({"tendril_edits": 1, "edits": [)" + edit + "]}", "edits.json"), "edits.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(R"({"at_step": 0, "edit": "add_obstacle"})").find("edits.json:/edits/0/path: is required"),
            std::string::npos);
  EXPECT_NE(error(R"({"at_step": 0, "edit": "add_obstacle", "path": "a.obj", "scale": 0})")
                .find("edits.json:/edits/0/scale"),
            std::string::npos);
  EXPECT_NE(error(R"({"at_step": 0, "edit": "move_obstacle", "obstacle": 0, "scale": "big"})")
                .find("edits.json:/edits/0/scale"),
            std::string::npos);
  EXPECT_NE(error(R"({"at_step": 0, "edit": "add_obstacle", "path": "a.obj", "colour": [1, 1, 1]})")
                .find("edits.json:/edits/0/colour"),
            std::string::npos);
}

// Session states written before obstacle scales and imports (version 1: transforms only) are
// still read, with every obstacle at scale 1.
TEST(ObstacleEdits, VersionOneStatesAreStillRead) {
  auto a = test::makeSession(test::sessionScene(test::kClimbPlant));
  for (int i = 0; i < 5; ++i) a->step();
  const std::vector<uint8_t> v2 = a->saveState();
  // Rewrite the state as version 1 wrote it: no scale after each transform, no import list.
  ArchiveReader in(v2, "v2");
  ArchiveWriter out;
  out.u32(in.u32());  // tag
  EXPECT_EQ(in.u32(), 2u);
  out.u32(1);
  out.u32(in.u32());  // steps
  const uint64_t plants = in.u64();
  out.u64(plants);
  for (uint64_t i = 0; i < 2 * plants; ++i) out.string(in.string());
  const uint64_t obstacles = in.u64();
  out.u64(obstacles);
  for (uint64_t o = 0; o < obstacles; ++o) {
    out.value(in.value<RigidTransform>());
    EXPECT_EQ(in.value<Vec3>(), Vec3::Ones());
  }
  EXPECT_EQ(in.u64(), 0u);  // imported obstacles
  std::vector<uint8_t> v1 = out.take();
  v1.insert(v1.end(), v2.begin() + std::ptrdiff_t(in.position()), v2.end());

  auto b = test::makeSession(test::sessionScene(test::kClimbPlant));
  b->loadState(v1, "v1");
  EXPECT_EQ(b->stateHash(), a->stateHash());
  EXPECT_EQ(b->saveState(), v2);
  v1[4] = 3;  // an unknown version is refused
  EXPECT_THROW(b->loadState(v1, "v1"), Error);
}

// `tendril edit` replays an import; a missing mesh is a one-line error naming it (exit 2).
TEST(ObstacleEdits, CliEditImportsAndNamesAMissingMesh) {
  auto dir = test::scratchDir();
  const fs::path wall = writeWall(dir);
  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/edit-stage.json");
  test::writeText(dir / "import.json",
                  fmt::format(R"({{"tendril_edits": 1, "edits": [{{"at_step": 0, "edit": "add_obstacle",
                      "path": "{}", "translation": [0, 0, 0.6]}}]}})",
                              wall.string()));
  auto ok = test::runTendril("edit " + scene + " --script " + test::quoted(dir / "import.json") + " --steps 3 -o " +
                                 test::quoted(dir / "a") + " --save " + test::quoted(dir / "a.tses") + " -q",
                             dir);
  ASSERT_EQ(ok.exitCode, 0) << ok.err;
  LoadedSession loaded = loadSession(dir / "a.tses");
  const size_t sceneObstacles = Session::open(test::sourceDir() / "examples/scenes/edit-stage.json")
                                    ->environment()
                                    .obstacleCount();
  EXPECT_EQ(loaded.session->environment().obstacleCount(), sceneObstacles + 1);

  test::writeText(dir / "missing.json", R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "add_obstacle",
                                            "path": "/no/such/post.obj"}]})");
  auto bad = test::runTendril("edit " + scene + " --script " + test::quoted(dir / "missing.json") + " -o " +
                                  test::quoted(dir / "b"),
                              dir);
  EXPECT_EQ(bad.exitCode, 2) << bad.err;
  EXPECT_NE(bad.err.find("/no/such/post.obj"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find((dir / "missing.json").string() + ":/edits/0: add_obstacle at step 0"), std::string::npos)
      << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "b/plant.glb"));  // nothing written
}

}  // namespace
}  // namespace tendril

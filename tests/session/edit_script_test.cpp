// Edit scripts: strict reading (errors name the file and the JSON pointer), replay that does
// not depend on the thread count, journals that replay to the same state, and the CLI.
#include "session/session_test_util.h"
#include "support/determinism.h"
#include "support/run_command.h"
#include "tendril/core/error.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace tendril {
namespace {

using namespace session;

const char* kScript = R"({"tendril_edits": 1, "edits": [
  {"at_step": 0, "edit": "seed_plant", "model": "climb", "position": [0.5, 0, 0.1], "seed": 3},
  {"at_step": 10, "edit": "paint_stroke", "radius": 0.3, "strength": 1, "points": [[0.3, 0.4, 0.02]]},
  {"at_step": 20, "edit": "move_obstacle", "obstacle": 1, "translation": [0, 0, -0.08], "rotation": [1, 0, 0, 0]},
  {"at_step": 25, "edit": "move_light", "light": 0, "direction": [0.5, -1, 0], "angular_radius": 2, "samples": 2},
  {"at_step": 30, "edit": "drag_begin", "plant": 0, "particle": 3, "target": [0.2, 0.2, 0.2], "strength": 0.4},
  {"at_step": 33, "edit": "drag_move", "target": [0.3, 0.25, 0.2]},
  {"at_step": 36, "edit": "drag_end"},
  {"at_step": 36, "edit": "cut", "plant": 1, "node": 4},
  {"at_step": 37, "edit": "paint_stroke", "kind": "repel", "radius": 0.2, "strength": 1, "points": [[0.6, 0.3, 0.02]]},
  {"at_step": 37, "edit": "cut", "plant": 0, "inside": {"min": [-1, 0.12, -1], "max": [1, 2, 1]},
   "remove": true},
  {"at_step": 38, "edit": "add_emitter", "position": [-1, 0.4, 0.2], "direction": [1, 0, 0], "speed": 3},
  {"at_step": 38, "edit": "set_species", "plant": 0, "species": {"particle_length": 0.05}},
  {"at_step": 39, "edit": "undo"},
  {"at_step": 39, "edit": "redo"},
  {"at_step": 40, "edit": "step", "count": 3}
]})";

std::string scriptError(const std::string& json) {
  try {
    parseEditScript(parseJson(json, "edits.json"), "edits.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(EditScript, ErrorsNameTheFileAndPointer) {
  EXPECT_EQ(scriptError(R"({"edits": []})"),
            "edits.json:/tendril_edits: is required: the edit script format version (this build reads 1)");
  EXPECT_EQ(scriptError(R"({"tendril_edits": 2, "edits": []})"),
            "edits.json:/tendril_edits: edit script version 2 is not supported (this build reads 1)");
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "seed"}]})")
                .find("edits.json:/edits/0/edit"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0, "node": 1,
                           "nodes": 2}]})")
                .find("edits.json:/edits/0/nodes"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0, "node": 1,
                           "particle": 2}]})")
                .find("edits.json:/edits/0/particle"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0}]})")
                .find("edits.json:/edits/0/node"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0, "node": 1,
                           "inside": {"min": [0, 0, 0], "max": [1, 1, 1]}}]})")
                .find("edits.json:/edits/0/inside"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0,
                           "inside": {"min": [0, 0, 0], "max": [1, -1, 1]}}]})")
                .find("edits.json:/edits/0/inside/max"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0,
                           "inside": {"min": [0, 0, 0]}}]})")
                .find("edits.json:/edits/0/inside/max"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 5, "edit": "undo"},
                                                          {"at_step": 2, "edit": "redo"}]})")
                .find("edits.json:/edits/1/at_step"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"edit": "undo"}]})").find("edits.json:/edits/0/at_step"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "paint_stroke",
                           "points": [[0, 1]]}]})")
                .find("edits.json:/edits/0/points/0"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "move_obstacle", "obstacle": 0,
                           "rotation": [2, 0, 0, 0]}]})")
                .find("edits.json:/edits/0/rotation"),
            std::string::npos);
  EXPECT_NE(scriptError(R"({"tendril_edits": 1, "edits": []})"), "no error") ;

  // An edit that does not fit the session names the script and the edit.
  auto s = test::makeSession(test::sessionScene(test::kParticlePlant));
  Editor editor(*s);
  EditScript bad = parseEditScript(
      parseJson(R"({"tendril_edits": 1, "edits": [{"at_step": 1, "edit": "step"},
                  {"at_step": 2, "edit": "cut", "plant": 4, "node": 0}]})",
                "edits.json"),
      "edits.json");
  try {
    runEditScript(editor, bad);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "edits.json:/edits/1: cut at step 2: /plant: there is no plant 4 (the session has 1)");
  }
}

uint64_t replay(const EditScript& script, std::vector<TimedEdit>* journal = nullptr) {
  auto s = test::makeSession(test::sessionScene(test::kParticlePlant + "," + test::kClimbPlant));
  Editor editor(*s);
  runEditScript(editor, script, 48);
  if (journal) *journal = editor.journal();
  return s->stateHash();
}

TEST(EditScript, EveryEditReplaysTheSameForAnyThreadCount) {
  const EditScript script = parseEditScript(parseJson(kScript, "edits.json"), "edits.json");
  std::vector<TimedEdit> journal;
  const uint64_t one = tendril::test::sameAtEveryThreadCount([&] { return replay(script, &journal); });
  // The journal, written as a script and read back, replays to the same state.
  const Json written = editScriptToJson(journal);
  const EditScript again = parseEditScript(parseJson(written.dump(), "journal"), "journal");
  EXPECT_EQ(replay(again), one);
  // Every kind of edit round-trips through JSON.
  for (const TimedEdit& t : script.edits) {
    Json j = editToJson(t.edit);
    JsonObject o(j, "edit");
    Edit back = readEdit(o);
    o.finish();
    EXPECT_EQ(editToJson(back), j);
  }
}

TEST(EditScript, ExampleScriptRunsOnTheDefaultScene) {
  const EditScript script = loadEditScript(test::sourceDir() / "examples/edits/edit-stage.json");
  auto s = Session::open(test::sourceDir() / "examples/scenes/edit-stage.json");
  Editor editor(*s);
  runEditScript(editor, script);
  EXPECT_GE(s->plantCount(), 2u);
  EXPECT_GE(s->environment().strokes().size(), 1u);
}

void expectOneLineError(const test::CommandResult& r, const std::string& prefix) {
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << "stderr: " << r.err;
}

TEST(EditCli, BadArgumentsAreOneLineErrors) {
  auto dir = test::scratchDir();
  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/edit-stage.json");
  expectOneLineError(test::runTendril("edit " + scene + " -o " + test::quoted(dir / "out"), dir),
                     "tendril: error: command line: --script is required");
  expectOneLineError(test::runTendril("edit " + scene + " --script " + test::quoted(dir / "none.json") + " -o " +
                                          test::quoted(dir / "out"),
                                      dir),
                     "tendril: error: " + (dir / "none.json").string() + ": edit script does not exist");
  test::writeText(dir / "bad.json", R"({"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "cut", "plant": 0}]})");
  expectOneLineError(test::runTendril("edit " + scene + " --script " + test::quoted(dir / "bad.json") + " -o " +
                                          test::quoted(dir / "out"),
                                      dir),
                     "tendril: error: " + (dir / "bad.json").string() + ":/edits/0/node: is required");
  expectOneLineError(test::runTendril("edit " + test::quoted(dir / "missing.json") + " --script " +
                                          test::quoted(dir / "bad.json") + " -o " + test::quoted(dir / "out"),
                                      dir),
                     "tendril: error: " + (dir / "missing.json").string() + ": scene or session file does not exist");
  expectOneLineError(test::runTendril("edit " + scene + " --script x.json -o out --steps -4", dir),
                     "tendril: error: command line: --steps");
}

TEST(EditCli, EditsSavesAndContinuesASession) {
  auto dir = test::scratchDir();
  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/edit-stage.json");
  const std::string script = test::quoted(test::sourceDir() / "examples/edits/edit-stage.json");
  auto first = test::runTendril("edit " + scene + " --script " + script + " --steps 60 -o " +
                                    test::quoted(dir / "a") + " --save " + test::quoted(dir / "a.tses") + " -q",
                                dir);
  ASSERT_EQ(first.exitCode, 0) << first.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "a/plant.glb"));
  ASSERT_TRUE(std::filesystem::exists(dir / "a.tses"));
  test::writeText(dir / "more.json", R"({"tendril_edits": 1, "edits": [{"at_step": 10, "edit": "step"}]})");
  // The session may be saved into the output directory the command makes.
  auto second = test::runTendril("edit " + test::quoted(dir / "a.tses") + " --script " + test::quoted(dir / "more.json") +
                                     " -o " + test::quoted(dir / "b") + " --save " + test::quoted(dir / "b/b.tses") +
                                     " -q",
                                 dir);
  ASSERT_EQ(second.exitCode, 0) << second.err;
  LoadedSession b = loadSession(dir / "b/b.tses");
  EXPECT_EQ(b.session->stepCount(), 71u);
  // The whole journal replays from the scene to the same state.
  auto replayed = Session::open(test::sourceDir() / "examples/scenes/edit-stage.json");
  Editor editor(*replayed);
  runEditScript(editor, EditScript{"journal", b.journal});
  EXPECT_EQ(replayed->stateHash(), b.session->stateHash());
}

}  // namespace
}  // namespace tendril

namespace tendril {
namespace {

TEST(EditCli, PreviewAndRenderOfASessionFile) {
  auto dir = test::scratchDir();
  const std::string scene = test::quoted(test::sourceDir() / "examples/scenes/edit-stage.json");
  const std::string script = test::quoted(test::sourceDir() / "examples/edits/edit-stage.json");
  auto edit = test::runTendril("edit " + scene + " --script " + script + " --steps 60 -o " + test::quoted(dir / "a") +
                                   " --save " + test::quoted(dir / "a.tses") + " --preview " +
                                   test::quoted(dir / "preview.png") + " -q",
                               dir);
  ASSERT_EQ(edit.exitCode, 0) << edit.err;
  EXPECT_GT(std::filesystem::file_size(dir / "preview.png"), 2000u);
  auto render = test::runTendril("render " + test::quoted(dir / "a.tses") + " -o " + test::quoted(dir / "r.png") +
                                     " --width 320 --height 180 -q",
                                 dir);
  ASSERT_EQ(render.exitCode, 0) << render.err;
  EXPECT_GT(std::filesystem::file_size(dir / "r.png"), 2000u);
  // A session keeps its seed; a damaged one is a one-line error naming it.
  auto seeded = test::runTendril("render " + test::quoted(dir / "a.tses") + " -o " + test::quoted(dir / "s.png") +
                                     " --seed 3",
                                 dir);
  EXPECT_EQ(seeded.exitCode, 2);
  std::string bytes = test::readText(dir / "a.tses");
  test::writeText(dir / "cut.tses", bytes.substr(0, bytes.size() / 2));
  auto damaged = test::runTendril("render " + test::quoted(dir / "cut.tses") + " -o " + test::quoted(dir / "d.png"), dir);
  EXPECT_EQ(damaged.exitCode, 2);
  EXPECT_EQ(damaged.err.rfind("tendril: error: " + (dir / "cut.tses").string() + ":byte ", 0), 0u) << damaged.err;
  EXPECT_EQ(std::count(damaged.err.begin(), damaged.err.end(), '\n'), 1) << damaged.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "d.png"));
}

}  // namespace
}  // namespace tendril

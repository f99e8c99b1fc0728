// The L-system editor's edit (set_grammar): a new grammar text re-derives the plant to the step
// it had reached, exactly as a plant given that text in the scene grows; undo restores the old
// grammar and plant exactly; a grammar with errors is an error at its line:col and changes
// nothing; session files keep the edited text.
#include "session/session_test_util.h"
#include "tendril/core/error.h"
#include "tendril/plant/plant_model.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

using namespace session;

// abop-1.24a with another rule (four segments where it had five) and a longer derivation.
const char* kEdited = R"(lsystem: edited
derivation length: 6
angle: 20
width: 0.25
axiom: F
F -> FF[+F][-F]
)";

std::string editedPlant(const std::string& extra = "") {
  Json p = parseJson(test::kLSystemPlant, "plant");
  p["grammar_text"] = kEdited;
  p.erase("derivation_length");
  const Json more = parseJson("{" + extra + "}", "extra");
  for (auto it = more.begin(); it != more.end(); ++it) p[it.key()] = it.value();
  return p.dump();
}

TEST(GrammarEdit, RederivesToTheStepReachedAndUndoesExactly) {
  auto s = test::makeSession(test::sessionScene(test::kLSystemPlant + "," + test::kParticlePlant));
  Editor editor(*s);
  editor.step(3);
  const uint64_t before = s->stateHash();
  const std::vector<uint8_t> bytes = s->saveState();
  const size_t nodesBefore = s->plants()[0].nodeCount();

  SetGrammar edit{0, kEdited, std::nullopt};
  editor.apply(edit);
  EXPECT_EQ(s->plantDescription(0)["grammar_text"], kEdited);
  EXPECT_EQ(s->plantDescription(0)["grammar"], "examples/grammars/abop-1.24a.ls");
  const uint64_t after = s->stateHash();
  EXPECT_NE(after, before);
  EXPECT_NE(s->plants()[0].nodeCount(), nodesBefore);

  // The same as a plant that had the edited text from the start, after the same 3 steps
  // (its own derivation_length of 4 from the scene is kept).
  Json reference = parseJson(editedPlant(R"("derivation_length": 4)"), "plant");
  auto fresh = test::makeSession(test::sessionScene(reference.dump() + "," + test::kParticlePlant));
  for (int i = 0; i < 3; ++i) fresh->step();
  EXPECT_EQ(plant::contentHash(s->plants()[0]), plant::contentHash(fresh->plants()[0]));
  // ... and it grows on the same.
  editor.step(2);
  fresh->step(), fresh->step();
  EXPECT_EQ(plant::contentHash(s->plants()[0]), plant::contentHash(fresh->plants()[0]));
  const uint64_t grown = s->stateHash();
  EXPECT_NE(grown, after);

  editor.undo();  // the edit and the two steps after it
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(s->saveState(), bytes);
  EXPECT_FALSE(s->plantDescription(0).contains("grammar_text"));
  editor.redo();
  EXPECT_EQ(s->stateHash(), grown);

  // A new derivation length: the plant grows on to it.
  editor.apply(SetGrammar{0, kEdited, 6});
  EXPECT_EQ(s->plantDescription(0)["derivation_length"], 6);
  const size_t atFour = s->plants()[0].nodeCount();  // derivation length 4 was reached
  editor.step(3);
  EXPECT_GT(s->plants()[0].nodeCount(), atFour);
}

TEST(GrammarEdit, ErrorsAreAtTheTextsLineAndColumnAndChangeNothing) {
  auto s = test::makeSession(test::sessionScene(test::kLSystemPlant + "," + test::kClimbPlant));
  Editor editor(*s);
  editor.step(2);
  const uint64_t before = s->stateHash();
  auto error = [&](const Edit& e) {
    try {
      editor.apply(e);
    } catch (const Error& err) {
      return std::string(err.what());
    }
    return std::string("no error");
  };
  const std::string bad = error(SetGrammar{0, "axiom: F\nF -> F[+F\n", std::nullopt});
  EXPECT_EQ(bad.rfind("set_grammar:/text 2:", 0), 0u) << bad;
  EXPECT_EQ(bad.find('\n'), std::string::npos) << bad;
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(error(SetGrammar{1, kEdited, std::nullopt}),
            "set_grammar:/plant: plant 1 is of model \"climb\"; only L-system plants have a grammar");
  EXPECT_NE(error(SetGrammar{5, kEdited, std::nullopt}).find("set_grammar:/plant"), std::string::npos);
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(editor.undoDepth(), 0u);
}

TEST(GrammarEdit, SessionFilesAndScriptsKeepTheText) {
  const std::string json = test::sessionScene(test::kLSystemPlant);
  auto a = test::makeSession(json);
  Editor editor(*a);
  editor.step(2);
  editor.apply(SetGrammar{0, kEdited, 5});
  editor.step(1);
  auto dir = test::scratchDir();
  saveSession(dir / "s.tses", *a, editor.journal());
  LoadedSession loaded = loadSession(dir / "s.tses");
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());
  for (int i = 0; i < 3; ++i) loaded.session->step(), a->step();
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());

  // The journal (with the text in it) replays to the same state and reads back as written.
  const Json written = editScriptToJson(loaded.journal);
  auto replayed = test::makeSession(json);
  Editor replayEditor(*replayed);
  runEditScript(replayEditor, parseEditScript(parseJson(written.dump(), "journal"), "journal"));
  for (int i = 0; i < 3; ++i) replayed->step();
  EXPECT_EQ(replayed->stateHash(), a->stateHash());
  Json j = editToJson(SetGrammar{0, kEdited, 5});
  EXPECT_EQ(j["edit"], "set_grammar");
  JsonObject o(j, "edit");
  Edit back = readEdit(o);
  o.finish();
  EXPECT_EQ(editToJson(back), j);

  // A scene may carry an edited grammar too; without "grammar" its textures resolve against
  // the scene's directory.
  Json plant = parseJson(editedPlant(), "plant");
  plant.erase("grammar");
  auto inline_ = test::makeSession(test::sessionScene(plant.dump()));
  for (int i = 0; i < 6; ++i) inline_->step();
  EXPECT_GT(inline_->plants()[0].nodeCount(), 100u);
}

}  // namespace
}  // namespace tendril

// The p-graph editor's edit (set_graph): a changed graph (a parameter, a new component and link,
// a deleted component) regenerates the plant at once, exactly as a plant given that graph in the
// scene; undo restores the old graph and plant exactly; a graph the reader refuses is an error
// at its JSON pointer and changes nothing; session files keep the edited graph.
#include "session/session_test_util.h"
#include "tendril/core/error.h"
#include "tendril/plant/plant_model.h"
#include "tendril/session/edit.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

namespace tendril {
namespace {

using namespace session;

Json fig2() { return readJsonFile(test::sourceDir() / "examples/graphs/fig2.json"); }

Json& component(Json& graph, const std::string& name) {
  for (Json& c : graph["components"])
    if (c["name"] == name) return c;
  throw std::runtime_error("no component " + name);
}

size_t primitives(const plant::PlantModel& m) { return m.primitives.size(); }

std::string errorOf(Editor& editor, const Edit& e) {
  try {
    editor.apply(e);
  } catch (const Error& err) {
    return err.what();
  }
  return "no error";
}

TEST(GraphEdit, ParameterComponentLinkAndDeleteAreUndoable) {
  auto s = test::makeSession(test::sessionScene(test::kGraphPlant + "," + test::kParticlePlant));
  Editor editor(*s);
  editor.step(2);
  const uint64_t before = s->stateHash();
  const std::vector<uint8_t> bytes = s->saveState();
  const plant::PlantModel original = s->plants()[0];
  // fig. 2: a Hydra of 3 with chains of 3 D horns, a bud at the end of each chain.
  ASSERT_EQ(primitives(original), 3u);

  // A parameter: the Hydra makes 4 chains.
  Json graph = fig2();
  component(graph, "C")["params"]["count"] = 4;
  editor.apply(SetGraph{0, graph});
  EXPECT_EQ(primitives(s->plants()[0]), 4u);
  EXPECT_GT(s->plants()[0].nodeCount(), original.nodeCount());
  EXPECT_EQ(s->plantDescription(0)["graph_document"], graph);
  const uint64_t fourChains = s->stateHash();
  // The same as a scene plant with that graph.
  Json described = parseJson(test::kGraphPlant, "plant");
  described["graph_document"] = graph;
  auto fresh = test::makeSession(test::sessionScene(described.dump()));
  EXPECT_EQ(plant::contentHash(fresh->plants()[0]), plant::contentHash(s->plants()[0]));

  // A new component linked under B: a sphere on top of the stem.
  graph["components"].push_back(Json{{"name", "knob"}, {"type", "simple"}, {"params", {{"shape", "sphere"}}}});
  component(graph, "B")["links"].push_back("knob");
  editor.apply(SetGraph{0, graph});
  EXPECT_EQ(primitives(s->plants()[0]), 5u);

  // Deleting the buds (the component and the link to it).
  component(graph, "D")["links"] = Json::array({"D"});
  graph["components"].erase(3);
  ASSERT_EQ(graph["components"][3]["name"], "knob");
  editor.apply(SetGraph{0, graph});
  EXPECT_EQ(primitives(s->plants()[0]), 1u);

  editor.undo(), editor.undo();
  EXPECT_EQ(s->stateHash(), fourChains);
  editor.undo();
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(s->saveState(), bytes);
  EXPECT_EQ(plant::contentHash(s->plants()[0]), plant::contentHash(original));
  editor.redo();
  EXPECT_EQ(s->stateHash(), fourChains);
}

TEST(GraphEdit, RefusedGraphsAreErrorsAtTheirPointerAndChangeNothing) {
  auto s = test::makeSession(test::sessionScene(test::kGraphPlant + "," + test::kClimbPlant));
  Editor editor(*s);
  const uint64_t before = s->stateHash();

  Json noDepth = fig2();
  component(noDepth, "D").erase("depth");  // D -> D is then a cycle without a depth
  const std::string cycle = errorOf(editor, SetGraph{0, noDepth});
  EXPECT_EQ(cycle.rfind("set_graph:/graph/components/2", 0), 0u) << cycle;

  Json typo = fig2();
  component(typo, "C")["params"]["cuont"] = 4;
  EXPECT_EQ(errorOf(editor, SetGraph{0, typo}).rfind("set_graph:/graph/components/1/params/cuont", 0), 0u);

  Json dangling = fig2();
  component(dangling, "B")["links"].push_back("nowhere");
  EXPECT_NE(errorOf(editor, SetGraph{0, dangling}).find("nowhere"), std::string::npos);

  EXPECT_EQ(errorOf(editor, SetGraph{1, fig2()}),
            "set_graph:/plant: plant 1 is of model \"climb\"; only graph plants have a p-graph");
  EXPECT_EQ(s->stateHash(), before);
  EXPECT_EQ(editor.undoDepth(), 0u);
}

TEST(GraphEdit, SessionFilesAndJsonKeepTheGraph) {
  const std::string json = test::sessionScene(test::kGraphPlant);
  auto a = test::makeSession(json);
  Editor editor(*a);
  Json graph = fig2();
  component(graph, "D")["params"]["length"] = 0.5;
  editor.apply(SetGraph{0, graph});
  auto dir = test::scratchDir();
  saveSession(dir / "s.tses", *a, editor.journal());
  LoadedSession loaded = loadSession(dir / "s.tses");
  EXPECT_EQ(loaded.session->stateHash(), a->stateHash());
  ASSERT_EQ(loaded.journal.size(), 1u);
  EXPECT_EQ(std::get<SetGraph>(loaded.journal[0].edit).graph, graph);

  Json j = editToJson(SetGraph{0, graph});
  EXPECT_EQ(j["edit"], "set_graph");
  JsonObject o(j, "edit");
  Edit back = readEdit(o);
  o.finish();
  EXPECT_EQ(editToJson(back), j);
}

}  // namespace
}  // namespace tendril

// `tendril model GRAPH -o OUT` and graph plants in scenes, as users meet them.
#include "graph_test_util.h"
#include "support/run_command.h"

#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <algorithm>

namespace tendril {
namespace {

using test::quoted;
using test::runTendril;

std::string example(const std::string& name) { return quoted(test::sourceDir() / "examples/graphs" / (name + ".json")); }

void expectOneLineError(const test::CommandResult& r, const std::string& prefix) {
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << "stderr: " << r.err;
}

TEST(GraphCli, ModelWritesGlbAndObj) {
  auto dir = test::scratchDir();
  auto r = runTendril("model " + example("sunflower") + " -o " + quoted(dir / "sunflower.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("instances"), std::string::npos) << r.err;  // the summary goes to the log
  auto v = test::validateGltf(dir / "sunflower.glb", dir);
  EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
  EXPECT_NE(v.out.find("errors=0"), std::string::npos) << v.out;

  auto obj = runTendril("model " + example("fig2") + " -o " + quoted(dir / "fig2.obj") + " -q", dir);
  ASSERT_EQ(obj.exitCode, 0) << obj.err;
  EXPECT_EQ(obj.err, "");
  EXPECT_TRUE(std::filesystem::exists(dir / "fig2.obj"));
  EXPECT_TRUE(std::filesystem::exists(dir / "fig2.mtl"));

  // --seed and --set change the plant; the same arguments give the same bytes.
  auto a = runTendril("model " + example("agave") + " -o " + quoted(dir / "a.glb") + " -q --threads 1", dir);
  auto b = runTendril("model " + example("agave") + " -o " + quoted(dir / "b.glb") + " -q --threads 2", dir);
  auto c = runTendril("model " + example("agave") + " -o " + quoted(dir / "c.glb") + " -q --seed 99", dir);
  auto d = runTendril("model " + example("agave") + " -o " + quoted(dir / "d.glb") + " -q --set rosette/count=12 " +
                          "--set 'leaf/curvature=40 * t'",
                      dir);
  ASSERT_EQ(a.exitCode + b.exitCode + c.exitCode + d.exitCode, 0) << a.err << b.err << c.err << d.err;
  std::string bytes = test::readText(dir / "a.glb");
  EXPECT_TRUE(bytes == test::readText(dir / "b.glb"));
  EXPECT_FALSE(bytes == test::readText(dir / "c.glb"));
  EXPECT_LT(test::readText(dir / "d.glb").size(), bytes.size());
}

// `tendril model` grows the one-plant scene it names: a scene file holding that graph plant,
// with the same seed, gives the same plant, byte for byte.
TEST(GraphCli, ModelIsTheOnePlantSceneOfItsGraph) {
  auto dir = test::scratchDir();
  auto scene = [&](const std::string& name, const std::string& seed, const std::string& output) {
    return R"({"tendril": 1, "output": {)" + output + R"(}, "plants": [{"name": ")" + name +
           R"(", "model": "graph", "graph": ")" + (test::sourceDir() / "examples/graphs" / (name + ".json")).string() +
           R"(", "position": [0, 0, 0])" + seed + "}]}";
  };
  auto r = runTendril("model " + example("agave") + " --seed 3 -q -o " + quoted(dir / "a.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  test::writeText(dir / "scene.json", scene("agave", R"(, "seed": 3)", ""));
  r = runTendril("grow " + quoted(dir / "scene.json") + " -q -o " + quoted(dir / "scene"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::string plant = test::readText(dir / "a.glb");
  EXPECT_GT(plant.size(), 10000u);
  EXPECT_TRUE(plant == test::readText(dir / "scene" / "plant.glb"));
  r = runTendril("model " + example("agave") + " --seed 4 -q -o " + quoted(dir / "b.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(plant == test::readText(dir / "b.glb"));
  // Without --seed, the graph's own; --radial-segments and --subdivisions are the scene's
  // output settings.
  r = runTendril("model " + example("sunflower") + " --radial-segments 5 --subdivisions 2 -q -o " + quoted(dir / "c.glb"),
                 dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  test::writeText(dir / "coarse.json", scene("sunflower", "", R"("radial_segments": 5, "subdivisions": 2)"));
  r = runTendril("grow " + quoted(dir / "coarse.json") + " -q -o " + quoted(dir / "coarse"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::string coarse = test::readText(dir / "c.glb");
  EXPECT_TRUE(coarse == test::readText(dir / "coarse" / "plant.glb"));
  r = runTendril("model " + example("sunflower") + " -q -o " + quoted(dir / "d.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_LT(coarse.size(), test::readText(dir / "d.glb").size());
}

TEST(GraphCli, BadInputIsOneLineAndExitCodeTwo) {
  auto dir = test::scratchDir();
  test::writeText(dir / "typo.json", R"j({"tendril_graph": 1, "root": {"links": ["s"]},
    "components": [{"name": "s", "type": "tree", "params": {"lenght": 2}}]})j");
  expectOneLineError(runTendril("model " + quoted(dir / "typo.json") + " -o " + quoted(dir / "x.glb"), dir),
                     "tendril: error: " + (dir / "typo.json").string() +
                         ":/components/0/params/lenght: unknown key \"lenght\" (did you mean \"length\"?)");
  // A file that is not JSON at all is reported at its line and column.
  test::writeText(dir / "broken.json", "{\"tendril_graph\": 1,\n \"components\": [{\"name\": \"s\",, }]}");
  expectOneLineError(runTendril("model " + quoted(dir / "broken.json") + " -o " + quoted(dir / "x.glb"), dir),
                     "tendril: error: " + (dir / "broken.json").string() + ":2:30: syntax error");
  test::writeText(dir / "divide.json", R"j({"tendril_graph": 1, "root": {"links": ["h"]},
    "components": [{"name": "h", "type": "hydra", "params": {"count": 4, "angle": "90 / (i - 1)"}}]})j");
  expectOneLineError(runTendril("model " + quoted(dir / "divide.json") + " -o " + quoted(dir / "x.glb"), dir),
                     "tendril: error: " + (dir / "divide.json").string() +
                         ":/components/0/params/angle: expression \"90 / (i - 1)\" evaluates to inf");
  expectOneLineError(runTendril("model " + example("fig2") + " -o " + quoted(dir / "x.png"), dir),
                     "tendril: error: command line:-o: the output must end in .glb or .obj");
  expectOneLineError(runTendril("model " + example("fig2") + " -o " + quoted(dir / "x.glb") + " --set D/sclae=2", dir),
                     "tendril: error: command line:--set D/sclae: override \"D/sclae\": a horn component has no "
                     "parameter \"sclae\"");
  expectOneLineError(runTendril("model " + quoted(dir / "missing.json") + " -o " + quoted(dir / "x.glb"), dir),
                     "tendril: error: " + (dir / "missing.json").string() + ": graph file does not exist");
  expectOneLineError(runTendril("model " + example("fig2") + " -o " + quoted(dir / "no" / "x.glb"), dir),
                     "tendril: error: " + (dir / "no" / "x.glb").string());
  // Nothing already saved is harmed.
  test::writeText(dir / "keep.glb", "old");
  auto r = runTendril("model " + quoted(dir / "divide.json") + " -o " + quoted(dir / "keep.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(test::readText(dir / "keep.glb"), "old");
}

std::string graphScene(const std::string& plantExtra) {
  return R"j({"tendril": 1, "steps": 5, "environment": {"obstacles": [{"type": "plane"}]},
    "plants": [{"name": "flower", "model": "graph", "graph": ")j" +
         (test::sourceDir() / "examples/graphs/fig2.json").string() + R"j(", "position": [1, 0, 2],
                "direction": [1, 1, 0])j" + plantExtra + "}]}";
}

TEST(GraphCli, ScenesPlaceGraphPlants) {
  auto dir = test::scratchDir();
  test::writeText(dir / "scene.json", graphScene(""));
  scene::Scene sc = scene::loadScene(dir / "scene.json");
  session::Session session(std::move(sc));
  EXPECT_TRUE(session.finished());  // a graph plant is static
  std::vector<plant::PlantModel> plants = session.plants();
  ASSERT_EQ(plants.size(), 1u);
  const plant::PlantModel& p = plants[0];
  EXPECT_EQ(p.name, "flower");
  // The root stem starts at the plant's position and grows along its direction.
  EXPECT_NEAR((p.position[0] - Vec3(1, 0, 2)).norm(), 0.0f, 1e-5f);
  EXPECT_NEAR((p.direction(0) - Vec3(1, 1, 0).normalized()).norm(), 0.0f, 1e-5f);
  // The same graph through the CLI's grow command exports a valid file.
  auto r = runTendril("grow " + quoted(dir / "scene.json") + " -o " + quoted(dir / "out") + " -q --format glb", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  auto v = test::validateGltf(dir / "out/plant.glb", dir);
  EXPECT_NE(v.out.find("errors=0"), std::string::npos) << v.out;

  // Overrides and seeds from the scene.
  test::writeText(dir / "override.json", graphScene(R"j(, "seed": 3, "overrides": {"C/count": 5})j"));
  std::vector<plant::PlantModel> five = session::Session(scene::loadScene(dir / "override.json")).plants();
  EXPECT_EQ(plant::computeStats(five[0]).tips, 5u);
  test::writeText(dir / "bad.json", graphScene(R"j(, "overrides": {"C/count": -2})j"));
  expectOneLineError(runTendril("validate " + quoted(dir / "bad.json"), dir),
                     "tendril: error: " + (dir / "bad.json").string() +
                         ":/plants/0/overrides/C~1count: must be in [0, 1000000], got -2");
  test::writeText(dir / "nograph.json", R"j({"tendril": 1, "plants": [{"model": "graph", "position": [0, 0, 0]}]})j");
  expectOneLineError(runTendril("validate " + quoted(dir / "nograph.json"), dir),
                     "tendril: error: " + (dir / "nograph.json").string() + ":/plants/0/graph: is required");
}

}  // namespace
}  // namespace tendril

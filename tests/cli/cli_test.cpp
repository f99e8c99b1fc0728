// The tendril command line as users meet it: exit codes, one-line errors naming the file and
// place, nothing lost on failure, and outputs that do not depend on the thread count.
#include "support/run_command.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace tendril {
namespace {

using test::quoted;
using test::runTendril;

// Exactly one line on stderr, starting with the given prefix.
void expectOneLineError(const test::CommandResult& r, const std::string& prefix) {
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << "stderr: " << r.err;
}

const char* kGood = R"({"tendril": 1, "steps": 40,
  "environment": {"obstacles": [{"type": "plane"}, {"name": "wall", "type": "wall", "size": [2, 2, 0.2]}],
                  "lights": [{"type": "directional"}]},
  "plants": [{"name": "ivy", "position": [0, 0, 0.12]}]})";

TEST(Cli, HelpAndVersion) {
  auto dir = test::scratchDir();
  auto help = runTendril("--help", dir);
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.out.find("grow"), std::string::npos);
  EXPECT_NE(help.out.find("validate"), std::string::npos);
  auto growHelp = runTendril("grow --help", dir);
  EXPECT_EQ(growHelp.exitCode, 0);
  EXPECT_NE(growHelp.out.find("--threads"), std::string::npos);
  auto version = runTendril("--version", dir);
  EXPECT_EQ(version.exitCode, 0);
  EXPECT_EQ(version.out, std::string("tendril ") + TENDRIL_VERSION + "\n");
}

TEST(Cli, GrowsTheDefaultSceneIntoValidFiles) {
  auto dir = test::scratchDir();
  auto r = runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/default.json") + " -o " +
                          quoted(dir / "out") + " --quiet",
                      dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  ASSERT_TRUE(std::filesystem::exists(dir / "out/plant.glb"));
  ASSERT_TRUE(std::filesystem::exists(dir / "out/plant.obj"));
  ASSERT_TRUE(std::filesystem::exists(dir / "out/plant.mtl"));
  EXPECT_GT(std::filesystem::file_size(dir / "out/plant.glb"), 100000u);
  auto v = test::validateGltf(dir / "out/plant.glb", dir);
  EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
  EXPECT_NE(v.out.find("errors=0"), std::string::npos) << v.out;
}

TEST(Cli, OutputIsBitIdenticalForAnyThreadCount) {
  auto dir = test::scratchDir();
  std::string scene = quoted(test::sourceDir() / "examples/scenes/default.json");
  auto one = runTendril("grow " + scene + " -o " + quoted(dir / "t1") + " --threads 1 --steps 150 -q", dir);
  auto two = runTendril("grow " + scene + " -o " + quoted(dir / "t2") + " --threads 2 --steps 150 -q", dir);
  auto again = runTendril("grow " + scene + " -o " + quoted(dir / "t3") + " --threads 2 --steps 150 -q", dir);
  ASSERT_EQ(one.exitCode, 0) << one.err;
  ASSERT_EQ(two.exitCode, 0) << two.err;
  ASSERT_EQ(again.exitCode, 0) << again.err;
  for (const char* f : {"plant.glb", "plant.obj"}) {
    std::string a = test::readText(dir / "t1" / f);
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == test::readText(dir / "t2" / f)) << f << " differs between 1 and 2 threads";
    EXPECT_TRUE(a == test::readText(dir / "t3" / f)) << f << " differs between two runs";
  }
  // --seed changes the plant.
  auto other = runTendril("grow " + scene + " -o " + quoted(dir / "t4") + " --seed 99 --steps 150 -q", dir);
  ASSERT_EQ(other.exitCode, 0);
  EXPECT_FALSE(test::readText(dir / "t1/plant.glb") == test::readText(dir / "t4/plant.glb"));
}

TEST(Cli, ValidateAcceptsGoodAndRejectsBadScenes) {
  auto dir = test::scratchDir();
  test::writeText(dir / "good.json", kGood);
  auto ok = runTendril("validate " + quoted(dir / "good.json"), dir);
  EXPECT_EQ(ok.exitCode, 0) << ok.err;
  test::writeText(dir / "bad.json", R"({"tendril": 1, "plants": [{"position": [0, 0, 0], "sed": 3}]})");
  expectOneLineError(runTendril("validate " + quoted(dir / "bad.json"), dir),
                     "tendril: error: " + (dir / "bad.json").string() +
                         ":/plants/0/sed: unknown key \"sed\" (did you mean \"seed\"?)");
}

TEST(Cli, ValidateReportsSeedsThatWillNotGrow) {
  // One ivy by a wall, one on open ground far from it: validate grows each alone for its first
  // steps and names the one that stops, with why; a seed that will not grow is a warning.
  auto dir = test::scratchDir();
  test::writeText(dir / "seeds.json", R"({"tendril": 1, "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [4, 4]},
      {"name": "wall", "type": "wall", "size": [2, 1.5, 0.1], "position": [0, 0, -0.05]}]},
      "plants": [{"name": "by-the-wall", "position": [0, 0, 0.05]}, {"name": "lost", "position": [0, 0, 1.5]}]})");
  auto r = runTendril("validate " + quoted(dir / "seeds.json"), dir);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("warning: " + (dir / "seeds.json").string() + ":/plants/1: plant \"lost\" stopped growing"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("no support in reach"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("by-the-wall"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 of the plants will not grow as their species does"), std::string::npos) << r.err;
}

struct BadScene {
  const char* name;
  const char* json;
  const char* expected;  // after "tendril: error: <file>"
};

TEST(Cli, BadScenesNameFileAndPlace) {
  const BadScene cases[] = {
      {"syntax", "{\n  \"tendril\": 1,\n  \"plants\": [,]\n}", ":3:14: syntax error"},
      {"unknown-key", R"({"tendril": 1, "environment": {"obstacles": [{"type": "box", "colour": [1, 0, 0]}]}})",
       ":/environment/obstacles/0/colour: unknown key \"colour\" (did you mean \"color\"?)"},
      {"wrong-type", R"({"tendril": 1, "steps": "many"})", ":/steps: expected an integer, got string \"many\""},
      {"out-of-range", R"({"tendril": 1, "plants": [{"position": [0, 0, 1], "species": {"decrease": {"radius": 1.5}}}]})",
       ":/plants/0/species/decrease/radius: must be in [0.5, 1], got 1.5"},
      {"bad-choice", R"({"tendril": 1, "environment": {"obstacles": [{"type": "cube"}]}})",
       ":/environment/obstacles/0/type: must be one of \"plane\", \"box\", \"sphere\", \"cylinder\", \"wall\", "
       "\"mesh\", got \"cube\""},
      {"version", R"({"tendril": 7})", ":/tendril: scene format version 7 is not supported (this build reads 1)"},
      {"no-version", R"({"plants": []})", ":/tendril: is required"},
      {"model", R"({"tendril": 1, "plants": [{"position": [0, 0, 1], "model": "triffid"}]})",
       ":/plants/0/model: must be one of \"climb\""},
      {"species", R"({"tendril": 1, "plants": [{"position": [0, 0, 1], "species": "kudzu"}]})",
       ":/plants/0/species: unknown species \"kudzu\""},
      {"opening", R"({"tendril": 1, "environment": {"obstacles": [{"type": "wall", "size": [2, 2, 0.2],
         "openings": [{"center": [0.9, 1], "size": [0.5, 0.5]}]}]}})",
       ":/environment/obstacles/0/openings: opening 0"},
      {"inside", R"({"tendril": 1, "environment": {"obstacles": [{"type": "box"}]}, "plants": [{"position": [0, 0, 0]}]})",
       ":/plants/0/position: seed position (0, 0, 0) lies inside an obstacle"},
      {"duplicate", R"({"tendril": 1, "plants": [{"name": "a", "position": [0, 0, 1]}, {"name": "a", "position": [1, 0, 1]}]})",
       ":/plants/1/name: plant name \"a\" is used twice"},
  };
  auto dir = test::scratchDir();
  for (const BadScene& c : cases) {
    SCOPED_TRACE(c.name);
    auto path = dir / (std::string(c.name) + ".json");
    test::writeText(path, c.json);
    expectOneLineError(runTendril("grow " + quoted(path) + " -o " + quoted(dir / "out"), dir),
                       "tendril: error: " + path.string() + c.expected);
    expectOneLineError(runTendril("validate " + quoted(path), dir), "tendril: error: " + path.string() + c.expected);
  }
}

TEST(Cli, BadMeshesNameTheirPath) {
  auto dir = test::scratchDir();
  test::writeText(dir / "empty.obj", "");
  test::writeText(dir / "bad.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [");
  test::writeText(dir / "cut.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 12\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n");
  for (const char* mesh : {"missing.obj", "empty.obj", "bad.gltf", "cut.ply"}) {
    SCOPED_TRACE(mesh);
    test::writeText(dir / "scene.json", std::string(R"({"tendril": 1, "environment": {"obstacles": [
        {"type": "mesh", "path": ")") + mesh + R"("}]}})");
    expectOneLineError(runTendril("validate " + quoted(dir / "scene.json"), dir),
                       "tendril: error: " + (dir / mesh).string() + ": ");
  }
}

TEST(Cli, BadArgumentsExitWithTwo) {
  auto dir = test::scratchDir();
  test::writeText(dir / "good.json", kGood);
  std::string scene = quoted(dir / "good.json");
  expectOneLineError(runTendril("grow " + scene, dir), "tendril: error: command line: ");  // no -o
  expectOneLineError(runTendril("grow " + scene + " -o x --frobnicate", dir), "tendril: error: command line: ");
  expectOneLineError(runTendril("grow " + scene + " -o x --threads -1", dir), "tendril: error: command line: ");
  expectOneLineError(runTendril("grow " + scene + " -o x --steps lots", dir), "tendril: error: command line: ");
  expectOneLineError(runTendril("grow " + scene + " -o " + quoted(dir / "x") + " --format fbx", dir),
                     "tendril: error: command line:--format: unknown format \"fbx\"");
  expectOneLineError(runTendril("explode", dir), "tendril: error: command line: ");
  expectOneLineError(runTendril("grow " + quoted(dir / "nope.json") + " -o x", dir),
                     "tendril: error: " + (dir / "nope.json").string() + ": scene file does not exist");
  test::writeText(dir / "a-file", "x");
  expectOneLineError(runTendril("grow " + scene + " -o " + quoted(dir / "a-file"), dir),
                     "tendril: error: command line:-o: " + (dir / "a-file").string() + " exists and is not a directory");
}

TEST(Cli, NothingIsLostWhenARunFails) {
  auto dir = test::scratchDir();
  std::filesystem::create_directories(dir / "out");
  test::writeText(dir / "out/plant.glb", "precious");
  test::writeText(dir / "bad.json", R"({"tendril": 1, "steps": -3})");
  auto r = runTendril("grow " + quoted(dir / "bad.json") + " -o " + quoted(dir / "out"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(test::readText(dir / "out/plant.glb"), "precious");
  // A good run replaces it, and leaves no temporary files behind.
  test::writeText(dir / "good.json", kGood);
  r = runTendril("grow " + quoted(dir / "good.json") + " -o " + quoted(dir / "out") + " -q", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(test::readText(dir / "out/plant.glb"), "precious");
  for (const auto& e : std::filesystem::directory_iterator(dir / "out"))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

}  // namespace
}  // namespace tendril

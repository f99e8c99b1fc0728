// `--format skeleton` from the command line (issue 26 part 5): `grow` and `edit` take it with
// glb and obj, `lsys` and `model` write it beside their -o file; the same run gives the same
// bytes at 1 and 2 threads, and a bad --format is still one line and exit code 2.
#include "support/run_command.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::readText;
using test::runTendril;

void expectOneLineError(const test::CommandResult& r, const std::string& prefix) {
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << "stderr: " << r.err;
}

const char* kScene = R"({"tendril": 1, "steps": 40,
  "environment": {"obstacles": [{"type": "plane"}, {"name": "wall", "type": "wall", "size": [2, 2, 0.2]}],
                  "lights": [{"type": "directional"}]},
  "plants": [{"name": "ivy", "position": [0, 0, 0.12]}]})";

size_t nodeCount(const fs::path& skeleton) {
  const nlohmann::json doc = nlohmann::json::parse(readText(skeleton));
  EXPECT_EQ(doc.at("format"), "tendril-skeleton");
  size_t n = 0;
  for (const auto& p : doc.at("plants")) n += p.at("nodes").size();
  return n;
}

TEST(SkeletonCli, GrowWritesTheSkeletonTheSameAtOneAndTwoThreads) {
  const fs::path dir = test::scratchDir();
  test::writeText(dir / "scene.json", kScene);
  const std::string scene = quoted(dir / "scene.json");
  auto r = runTendril("grow " + scene + " -q --threads 1 --format glb,skeleton -o " + quoted(dir / "one"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = runTendril("grow " + scene + " -q --threads 2 --format skeleton,glb -o " + quoted(dir / "two"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* f : {"plant.skeleton.json", "plant.glb"}) {
    SCOPED_TRACE(f);
    ASSERT_TRUE(fs::exists(dir / "one" / f));
    EXPECT_EQ(readText(dir / "one" / f), readText(dir / "two" / f));
  }
  EXPECT_FALSE(fs::exists(dir / "one/plant.obj"));
  EXPECT_GT(nodeCount(dir / "one/plant.skeleton.json"), 20u);
  // The skeleton alone: no meshes written.
  r = runTendril("grow " + scene + " -q --format skeleton -o " + quoted(dir / "alone"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readText(dir / "alone/plant.skeleton.json"), readText(dir / "one/plant.skeleton.json"));
  EXPECT_FALSE(fs::exists(dir / "alone/plant.glb"));
  EXPECT_FALSE(fs::exists(dir / "alone/plant.obj"));
}

TEST(SkeletonCli, LsysAndModelWriteItBesideTheirOutput) {
  const fs::path dir = test::scratchDir();
  const std::string grammar = quoted(test::sourceDir() / "examples/grammars/abop-2.6-monopodial.ls");
  const std::string graph = quoted(test::sourceDir() / "examples/graphs/fig2.json");
  // Without --format: the output's extension, as before.
  auto r = runTendril("lsys " + grammar + " -q -o " + quoted(dir / "plain.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = runTendril("lsys " + grammar + " -q --format glb,skeleton -o " + quoted(dir / "tree.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readText(dir / "tree.glb"), readText(dir / "plain.glb"));
  EXPECT_GT(nodeCount(dir / "tree.skeleton.json"), 10u);
  EXPECT_FALSE(fs::exists(dir / "plain.skeleton.json"));

  r = runTendril("model " + graph + " -q -o " + quoted(dir / "fig2.obj") + " --format skeleton", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_GT(nodeCount(dir / "fig2.skeleton.json"), 10u);
  EXPECT_FALSE(fs::exists(dir / "fig2.obj"));
  r = runTendril("model " + graph + " -q -o " + quoted(dir / "both.glb") + " --format skeleton,glb,obj", dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* f : {"both.glb", "both.obj", "both.mtl"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_EQ(readText(dir / "both.skeleton.json"), readText(dir / "fig2.skeleton.json"));
}

TEST(SkeletonCli, BadFormatsAreOneLineErrors) {
  const fs::path dir = test::scratchDir();
  test::writeText(dir / "scene.json", kScene);
  const std::string scene = quoted(dir / "scene.json");
  const std::string prefix = "tendril: error: command line:--format: unknown format ";
  expectOneLineError(runTendril("grow " + scene + " -o " + quoted(dir / "x") + " --format glb,skel", dir),
                     prefix + "\"skel\" (expected glb, obj, skeleton or a comma-separated list of them)");
  expectOneLineError(runTendril("grow " + scene + " -o " + quoted(dir / "x") + " --format skeleton,", dir),
                     prefix + "\"\"");
  expectOneLineError(runTendril("edit " + scene + " --script " + quoted(dir / "none.json") + " -o " +
                                    quoted(dir / "x") + " --format json",
                                dir),
                     prefix + "\"json\"");
  expectOneLineError(runTendril("lsys algae -o " + quoted(dir / "a.glb") + " --format Skeleton", dir),
                     prefix + "\"Skeleton\"");
  expectOneLineError(runTendril("model " + quoted(test::sourceDir() / "examples/graphs/fig2.json") + " -o " +
                                    quoted(dir / "f.glb") + " --format glb,,obj",
                                dir),
                     prefix + "\"\"");
  EXPECT_FALSE(fs::exists(dir / "x"));
  EXPECT_FALSE(fs::exists(dir / "a.glb"));
  EXPECT_FALSE(fs::exists(dir / "f.glb"));
}

}  // namespace
}  // namespace tendril

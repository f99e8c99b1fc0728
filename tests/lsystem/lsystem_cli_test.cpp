// `tendril lsys` and scene plants with "model": "lsystem": exit codes, one-line errors with the
// grammar line and a caret under them, valid output.
#include "lsystem/lsystem_test_util.h"
#include "support/run_command.h"

#include "tendril/core/json_reader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>

namespace tendril::lsystem {
namespace {

using tendril::test::quoted;
using tendril::test::runTendril;
using tendril::test::scratchDir;
using tendril::test::writeText;

std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

TEST(LSystemCli, DerivesAGrammarIntoAValidGlb) {
  auto dir = scratchDir();
  auto r = runTendril("lsys " + quoted(test::grammarPath("abop-1.24d.ls")) + " -n 4 -o " + quoted(dir / "d.glb"),
                      dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  auto v = tendril::test::validateGltf(dir / "d.glb", dir);
  EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
  // A built-in name, .obj output, --print, --seed and --define.
  r = runTendril("lsys abop-1.27-stochastic -n 2 --seed 4 --print -q -o " + quoted(dir / "s.obj"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "s.obj"));
  std::string printed = firstLine(r.out);
  EXPECT_EQ(printed.find_first_not_of("F[]+-"), std::string::npos) << printed;
  auto again = runTendril("lsys abop-1.27-stochastic -n 2 --seed 4 --print -q -o " + quoted(dir / "s.obj"), dir);
  EXPECT_EQ(again.out, r.out);
  r = runTendril("lsys abop-2.6-monopodial -D r1=0.5 -D d=90 -q -o " + quoted(dir / "m.glb"), dir);
  EXPECT_EQ(r.exitCode, 0) << r.err;
}

TEST(LSystemCli, ParseErrorsPrintTheLineWithACaretAndExit2) {
  auto dir = scratchDir();
  writeText(dir / "bad.ls", "axiom: A\nA -> B(1 +)\n");
  auto r = runTendril("lsys " + quoted(dir / "bad.ls") + " -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "bad.ls").string() +
                       ":2:11: expected a number, a name or '(', found ')'\n 2 | A -> B(1 +)\n   |           ^\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "x.glb"));
}

TEST(LSystemCli, RunTimeErrorsNameTheRuleAndExit2) {
  auto dir = scratchDir();
  writeText(dir / "div.ls", "derivation length: 3\naxiom: A(2)\nA(x) -> A(x - 1) B(1 / x)\n");
  auto r = runTendril("lsys " + quoted(dir / "div.ls") + " -q -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "div.ls").string() +
                       ":3:22: division by zero in production `A(x) -> A(x - 1) B(1 / x)` (rewriting module 0, A(0), "
                       "in step 3)\n 3 | A(x) -> A(x - 1) B(1 / x)\n   |                      ^\n");
  // Errors of the Start: block (run as the plant is seeded) keep their line and caret too.
  writeText(dir / "start.ls", "derivation length: 2\nStart: { z = 0; y = 1 / z; }\naxiom: A\nA -> F A\n");
  r = runTendril("lsys " + quoted(dir / "start.ls") + " -q -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "start.ls").string() +
                       ":2:23: division by zero in the Start block\n 2 | Start: { z = 0; y = 1 / z; }\n   |     "
                       "                  ^\n");
  writeText(dir / "big.ls", "max length: 100\nderivation length: 10\naxiom: A\nA -> A A\n");
  r = runTendril("lsys " + quoted(dir / "big.ls") + " -q -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "big.ls").string() +
                       ": step 7 would make the string longer than 100 modules (its limit); raise `max length:` in "
                       "the grammar, or derive fewer steps\n");
}

TEST(LSystemCli, CommandLineErrorsExit2) {
  auto dir = scratchDir();
  auto r = runTendril("lsys abop-1.24a -o " + quoted(dir / "x.png"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: command line:-o: the output must end in .glb or .obj, got \"" +
                       (dir / "x.png").string() + "\"\n");
  r = runTendril("lsys no-such-grammar -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(firstLine(r.err).rfind("tendril: error: command line:GRAMMAR: unknown grammar \"no-such-grammar\" "
                                   "(built-in: ",
                                   0),
            0u)
      << r.err;
  r = runTendril("lsys abop-1.24a -D r1 -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: command line:--define: expected NAME=NUMBER, got \"r1\"\n");
  r = runTendril("lsys abop-1.24a -D nope=1 -o " + quoted(dir / "x.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: <built-in>/grammars/abop-1.24a.ls: cannot set \"nope\": the grammar defines no "
                   "such constant (its define: constants: none)\n");
}

TEST(LSystemCli, AtPlacesThePlantInAScene) {
  auto dir = scratchDir();
  const std::string scene = quoted(tendril::test::sourceDir() / "examples/scenes/default.json");
  // The default scene's wall stands at the origin: starting there is an error, not a stump.
  auto r = runTendril("lsys japanese-ivy -n 60 --scene " + scene + " -o " + quoted(dir / "a.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err, "tendril: error: command line:--at: seed position (0, 0, 0) lies inside an obstacle of " +
                       (tendril::test::sourceDir() / "examples/scenes/default.json").string() +
                       "; give --at x,y,z in front of a surface\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "a.glb"));
  // In front of the wall it climbs.
  r = runTendril("lsys japanese-ivy -n 60 --scene " + scene + " --at -1.1,0.02,0.15 -o " + quoted(dir / "b.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("segments"), std::string::npos);
  r = runTendril("lsys japanese-ivy --at 1,2 -o " + quoted(dir / "c.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("command line:--at: expected three comma-separated numbers"), std::string::npos) << r.err;
  r = runTendril("lsys japanese-ivy --heading 0,0,0 -o " + quoted(dir / "c.glb"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("command line:--heading: the heading must not be zero"), std::string::npos) << r.err;
}

// `tendril lsys` grows the one-plant scene it names: a scene file holding that plant, with the
// same seed, gives the same plant, byte for byte.
TEST(LSystemCli, IsTheOnePlantSceneOfItsGrammar) {
  auto dir = scratchDir();
  auto r = runTendril("lsys abop-1.27-stochastic --seed 3 -q -o " + quoted(dir / "a.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  writeText(dir / "scene.json", R"({"tendril": 1, "steps": 10, "plants": [
      {"name": "abop-1.27", "model": "lsystem", "grammar": "abop-1.27-stochastic", "position": [0, 0, 0], "seed": 3}]})");
  r = runTendril("grow " + quoted(dir / "scene.json") + " --format glb -q -o " + quoted(dir / "scene"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::string plant = tendril::test::readText(dir / "a.glb");
  EXPECT_FALSE(plant.empty());
  EXPECT_TRUE(plant == tendril::test::readText(dir / "scene" / "plant.glb"));
  // Another seed is another plant.
  r = runTendril("lsys abop-1.27-stochastic --seed 4 -q -o " + quoted(dir / "b.glb"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(plant == tendril::test::readText(dir / "b.glb"));

  // In a scene (its environment, its seed 7, its output settings) at --at, derived -n steps.
  const std::filesystem::path example = tendril::test::sourceDir() / "examples/scenes/ivy-lsystem.json";
  r = runTendril("lsys japanese-ivy -n 25 --seed 2 --scene " + quoted(example) + " --at 0.75,0,0.15 -q -o " +
                     quoted(dir / "c.glb"),
                 dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  Json doc = parseJson(tendril::test::readText(example), example.string());
  doc["steps"] = 25;
  doc["plants"] = Json::parse(R"([{"name": "japanese-ivy", "model": "lsystem", "grammar": "japanese-ivy",
      "position": [0.75, 0, 0.15], "seed": 2, "derivation_length": 25}])");
  writeText(dir / "ivy.json", doc.dump());
  r = runTendril("grow " + quoted(dir / "ivy.json") + " --format glb -q -o " + quoted(dir / "ivy"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::string ivy = tendril::test::readText(dir / "c.glb");
  EXPECT_GT(ivy.size(), 10000u);
  EXPECT_TRUE(ivy == tendril::test::readText(dir / "ivy" / "plant.glb"));
}

TEST(LSystemCli, ScenePlantsWithTheLSystemModel) {
  auto dir = scratchDir();
  writeText(dir / "tree.ls", "derivation length: 4\ndefine: a = 30\nangle: a\naxiom: X\nX -> F[+X][-X]FX\nF -> FF\n");
  writeText(dir / "scene.json", R"({"tendril": 1, "steps": 10, "plants": [
      {"name": "tree", "model": "lsystem", "grammar": "tree.ls", "position": [1, 0, 0], "define": {"a": 20}},
      {"name": "ivy", "model": "lsystem", "grammar": "abop-1.24a", "position": [-1, 0, 0], "derivation_length": 2}]})");
  auto r = runTendril("grow " + quoted(dir / "scene.json") + " -q -o " + quoted(dir / "out"), dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  auto v = tendril::test::validateGltf(dir / "out" / "plant.glb", dir);
  EXPECT_EQ(v.exitCode, 0) << v.out << v.err;

  writeText(dir / "missing.json", R"({"tendril": 1, "plants": [{"model": "lsystem", "position": [0, 0, 0]}]})");
  r = runTendril("grow " + quoted(dir / "missing.json") + " -o " + quoted(dir / "out"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "missing.json").string() +
                       ":/plants/0/grammar: is required: a built-in grammar name (e.g. \"japanese-ivy\") or a path to "
                       "a .ls file\n");
  writeText(dir / "define.json", R"({"tendril": 1, "plants": [{"model": "lsystem", "grammar": "tree.ls",
      "position": [0, 0, 0], "define": {"b": 1}}]})");
  r = runTendril("grow " + quoted(dir / "define.json") + " -o " + quoted(dir / "out"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(r.err, "tendril: error: " + (dir / "define.json").string() + ":/plants/0/define/b: grammar " +
                       (dir / "tree.ls").string() + " has no define: constant \"b\" (its constants: a)\n");
  writeText(dir / "typo.json", R"({"tendril": 1, "plants": [{"model": "lsystem", "grammar": "tree.ls",
      "position": [0, 0, 0], "derivaton_length": 3}]})");
  r = runTendril("grow " + quoted(dir / "typo.json") + " -o " + quoted(dir / "out"), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("derivation_length"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace tendril::lsystem

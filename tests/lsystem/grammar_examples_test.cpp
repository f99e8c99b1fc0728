// Every grammar in examples/grammars derives and draws a plant that exports to a .glb the
// Khronos validator accepts.
#include "lsystem/lsystem_test_util.h"
#include "support/gltf_validator.h"
#include "tendril/io/gltf_writer.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace tendril::lsystem {
namespace {

TEST(GrammarExamples, EveryExampleDerivesAndExportsAValidGlb) {
  auto dir = meshtest::exportTestDir();
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(test::grammarPath("")))
    if (e.path().extension() == ".ls") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 12u);
  for (const auto& f : files) {
    SCOPED_TRACE(f.filename().string());
    LSystem ls(loadGrammarFile(f));
    ls.derive();  // in an empty world: environment queries find nothing
    plant::PlantModel p = ls.interpret();
    p.name = f.stem().string();
    plant::validate(p, f.string());
    EXPECT_GT(p.nodeCount(), 0u);
    io::ExportScene scene;
    scene.plants.push_back(std::move(p));
    std::filesystem::path out = dir / (f.stem().string() + ".glb");
    io::writeGlb(scene, out);
    meshtest::GltfValidation v = meshtest::validateGltf(out);
    EXPECT_EQ(v.errors, 0) << v.output;
    EXPECT_EQ(v.warnings, 0) << v.output;
  }
}

TEST(GrammarExamples, BuiltInNamesFindTheExampleFiles) {
  std::vector<std::string> names = builtinGrammarNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "japanese-ivy"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "abop-1.24a"), names.end());
  auto g = loadGrammar("abop-1.24a", "/nonexistent");
  EXPECT_EQ(g->name, "abop-1.24a");
  try {
    loadGrammar("no-such-grammar", "", {}, "scene.json", "/plants/0/grammar");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "/plants/0/grammar");
    EXPECT_NE(e.message().find("unknown grammar \"no-such-grammar\" (built-in: "), std::string::npos);
  }
  try {
    loadGrammar("missing.ls", "/tmp", {}, "scene.json", "/plants/0/grammar");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "scene.json:/plants/0/grammar: grammar file /tmp/missing.ls does not exist");
  }
}

TEST(GrammarExamples, FlowerPolygonsAndTreeTropism) {
  // The flowering plant draws polygons in several colours; the tropism tree bends down.
  LSystem flower(loadGrammarFile(test::grammarPath("abop-1.26-flower.ls")));
  flower.derive();
  plant::PlantModel f = flower.interpret();
  EXPECT_EQ(f.meshes.size(), 2u);  // green leaves, yellow petals
  LSystem tree(loadGrammarFile(test::grammarPath("abop-2.8-tropism.ls")));
  tree.derive();
  plant::PlantModel t = tree.interpret();
  float down = 0;
  for (size_t i = 0; i < t.nodeCount(); ++i) down = std::min(down, t.direction(i).y());
  EXPECT_LT(down, 0.0f);  // some branches hang below the horizontal
}

TEST(GrammarExamples, LychnisFlowersOnTheScheduleItsApicesImply) {
  // ABOP ch. 3: the apex flowers in step 1; each flowering makes apices that flower 4 and 8
  // steps later, so the flowers by step n number c(n) = 1 + c(n - 4) + c(n - 8) (0 for n < 1),
  // and every flower comes with two leaves.
  auto flowersBy = [](int n) {
    std::vector<size_t> c(size_t(std::max(n, 0)) + 1, 0);
    for (int k = 1; k <= n; ++k) c[size_t(k)] = 1 + (k > 4 ? c[size_t(k - 4)] : 0) + (k > 8 ? c[size_t(k - 8)] : 0);
    return c[size_t(std::max(n, 0))];
  };
  LSystem ls(loadGrammarFile(test::grammarPath("abop-ch3-lychnis.ls")));
  ASSERT_EQ(ls.derivationLength(), 26);
  for (int n = 1; n <= 26; ++n) {
    ls.step();
    ASSERT_EQ(test::countOf(ls, "~K"), flowersBy(n)) << "after step " << n;
    ASSERT_EQ(test::countOf(ls, "~leaf"), 2 * flowersBy(n)) << "after step " << n;
  }
  EXPECT_EQ(flowersBy(26), 33u);
  plant::PlantModel p = ls.interpret();
  EXPECT_EQ(p.leafCount(), 66u);
  ASSERT_EQ(p.meshes.size(), 1u);  // the petals: five two-sided rhombi per flower
  EXPECT_EQ(p.meshes[0].mesh.triangleCount(), 33u * 5 * 2 * 2);
}

}  // namespace
}  // namespace tendril::lsystem
